/* Host unit tests of core/sma.c's coil heat ceiling (builds with CFG_COIL_TAU_MS: the robot file's
 * opt-in [safety] coil_heat_ceiling = true).
 * Config (r1-heat): the paper robots' envelope (max_duty 0.8, max_on 3000 ms, min_cooldown 800 ms,
 * hold ceiling 3000 ‱, mean duty 4500 ‱ over 10 s), 1 kHz, coil_heat_ceiling = true, so the
 * coils' time constant CFG_COIL_TAU_MS (1259 ms, the BMX100-class coil) is built in. Time comes
 * from fake_now_us only. */
#include <math.h>

#include "fake_hal.h"
#include "sma.h"
#include "unit.h"

#define TAU_S (CFG_COIL_TAU_MS / 1000.0)
#define MEAN (CFG_MEAN_DUTY_PM / 10000.0)

static double model; /* the test's own first-order coil: the applied duty smoothed with tau */

static void setup(void)
{
    fake_hal_reset();
    fake_now_us = 0;
    sma_init(0);
    model = 0.0;
}

/* One control tick of `us` µs; the model is charged with the duty the pin carried in it. */
static void tick_us(uint32_t us)
{
    double carried = fake_pwm[0] / 10000.0;
    fake_now_us += us;
    model += (carried - model) * (1.0 - exp(-(us / 1e6) / TAU_S));
    sma_tick(0);
}

/* `s` seconds of 1 ms ticks asking channel 0 for `duty`; returns the seconds it got more than the mean-duty ceiling. */
static double ask(uint16_t duty, double s)
{
    double above = 0.0;
    long n = lround(s * 1000.0);
    while (n-- > 0) {
        sma_request(0, duty);
        tick_us(1000);
        if (fake_pwm[0] > CFG_MEAN_DUTY_PM) {
            above += 1e-3;
        }
    }
    return above;
}

static void test_the_build_carries_the_coils_time_constant(void)
{
    CHECK_EQ(CFG_COIL_TAU_MS, 1259);
    CHECK_EQ(CFG_MAX_ON_MS, 3000);
    CHECK_EQ(CFG_MEAN_DUTY_PM, 4500);
}

static void test_a_drive_from_cold_runs_until_the_heat_reaches_the_mean_duty_ceiling(void)
{
    /* 0.6 from cold: the smoothed duty reaches 0.45 after tau × ln(0.6 / 0.15) = 1.75 s, long
     * before max_on (3 s); a gait's rise (≈ 1.2 s at 0.6) never meets it */
    double t;
    setup();
    t = ask(6000, 1.7);
    CHECK(t > 1.69);
    CHECK_EQ(fake_pwm[0], 6000);
    ask(6000, 0.1);
    CHECK_EQ(fake_pwm[0], CFG_MEAN_DUTY_PM); /* the duty that keeps it at the ceiling, not off */
    ask(6000, 1.0);
    CHECK_EQ(fake_pwm[0], CFG_MEAN_DUTY_PM);
    CHECK(model <= MEAN + 0.002);
}

static void test_stop_and_start_forgive_the_debt_but_not_the_heat(void)
{
    /* inchworm-3's restart: 1.6 s at 0.6, a STOP, 0.45 s off (the debt, paid back at 3000/800, is
     * 0 after 0.43 s), a START: the debt gave a fresh max_on (3 s more at 0.6: 138 °C on the
     * physical plant); the heat gives what the coil's warmth leaves, under a second */
    double t;
    setup();
    ask(6000, 1.6);
    sma_all_off();
    ask(0, 0.45);
    CHECK_EQ(sma_debt_us(0), 0);
    t = ask(6000, 3.0);
    CHECK(t < 1.0); /* 0.6 until the heat is back at the ceiling: 0.9 s here */
    CHECK(model <= MEAN + 0.002);
}

static void test_estop_and_clear_refund_no_heat(void)
{
    double t;
    /* 0.8 until the heat caps it, an ESTOP of 0.05 s (the debt pays back 0.19 s of on-time in
     * it), CLEAR: the coil is still hot, 0.8 only until the heat is back at the ceiling */
    setup();
    ask(8000, 1.3);
    CHECK_EQ(fake_pwm[0], CFG_MEAN_DUTY_PM);
    sma_estop();
    ask(8000, 0.05);
    sma_clear_estop();
    t = ask(8000, 0.2);
    CHECK(t < 0.08); /* what 0.05 s of cooling earned back: 0.06 s at 0.8 (the debt: all 0.2 s) */
    CHECK(model <= MEAN + 0.002);
}

static void test_no_host_pattern_heats_a_coil_past_the_mean_duty_ceiling_held_for_ever(void)
{
    /* 120 s of a host's pattern: runs of the duty ceiling, of the drive duty and of nothing,
     * STOPs and ESTOP + CLEAR between ticks, ticks from 0.2 to 30 ms; the test's own model of the
     * coil (the duty the pin carried, smoothed exactly with tau) never passes the mean-duty
     * ceiling by more than one tick's rise */
    uint32_t seed = 12345u;
    double peak = 0.0;
    long k;
    setup();
    for (k = 0; k < 40000; k++) {
        uint32_t r;
        seed = seed * 1103515245u + 12345u;
        r = (seed >> 8) & 0xFFFFu;
        if ((k / 700) % 3 == 0) {
            sma_request(0, 8000);
        } else if ((k / 700) % 3 == 1) {
            sma_request(0, (r & 1u) ? 6000 : 0);
        } else if (r % 5u == 0u) {
            sma_request(0, 8000);
        }
        if (r % 97u == 0u) {
            sma_all_off(); /* STOP ... */
            sma_request(0, 8000); /* ... START in the same tick */
        }
        if (r % 1999u == 0u) {
            sma_estop();
            sma_clear_estop();
            sma_request(0, 8000);
        }
        tick_us(200u + (r % 30u == 0u ? 29800u : r % 3000u));
        if (model > peak) {
            peak = model;
        }
    }
    CHECK(peak <= MEAN + 0.8 * 0.03 + 0.002); /* one 30 ms tick at 0.8 adds at most 0.8 × 30 / 1259 */
    CHECK(peak > MEAN - 0.05);                /* and it was asked for all of it */
}

static void test_holding_at_or_below_the_hold_ceiling_is_never_capped(void)
{
    setup();
    ask(CFG_HOLD_MAX_DUTY_PM, 60.0);
    CHECK_EQ(fake_pwm[0], CFG_HOLD_MAX_DUTY_PM);
    CHECK(model > 0.29);
}

/* A reset that is not a power-on keeps the heat: a coil at the ceiling gets the ceiling's duty
 * right after it, and after a power-on the full drive (docs/safety.md, "A reset"). */
static void test_a_warm_reset_keeps_the_heat_a_cold_one_forgets(void)
{
    uint8_t warm;
    for (warm = 0; warm < 2; warm++) {
        setup();
        ask(6000, 2.5);
        CHECK_EQ(fake_pwm[0], CFG_MEAN_DUTY_PM);
        fake_now_us = 777u; /* the chip's clock starts over */
        sma_init(warm);
        ask(6000, 0.01);
        CHECK_EQ(fake_pwm[0], warm ? CFG_MEAN_DUTY_PM : 6000u);
    }
}

int main(void)
{
    RUN(test_the_build_carries_the_coils_time_constant);
    RUN(test_a_drive_from_cold_runs_until_the_heat_reaches_the_mean_duty_ceiling);
    RUN(test_stop_and_start_forgive_the_debt_but_not_the_heat);
    RUN(test_estop_and_clear_refund_no_heat);
    RUN(test_no_host_pattern_heats_a_coil_past_the_mean_duty_ceiling_held_for_ever);
    RUN(test_holding_at_or_below_the_hold_ceiling_is_never_capped);
    RUN(test_a_warm_reset_keeps_the_heat_a_cold_one_forgets);
    return UNIT_EXIT();
}
