/* Host unit tests of core/sma.c, the thermal budget of every SMA coil. Config (r1-fast):
 * max_duty 0.8 (8000 ‱), max_on 50 ms, min_cooldown 20 ms, 1 kHz tick; budget defaults:
 * hold ceiling 3000 ‱, mean duty 4500 ‱ over 10 s. Time comes from fake_now_us only. */
#include <string.h>

#include "fake_hal.h"
#include "sma.h"
#include "unit.h"

#define MAX_ON_US (CFG_MAX_ON_MS * 1000UL)
#define COOL_US (CFG_MIN_COOLDOWN_MS * 1000UL)

static void setup_at(uint64_t t0)
{
    fake_hal_reset();
    fake_now_us = t0;
    sma_init(0);
}

static void setup(void)
{
    setup_at(0);
}

/* One control tick of `us` real microseconds. */
static uint8_t tick_us(uint32_t us)
{
    fake_now_us += us;
    return sma_tick(0);
}

static uint8_t tick(void)
{
    return tick_us(CFG_TICK_US);
}

static void test_init_turns_every_board_channel_off(void)
{
    uint8_t ch;
    setup();
    for (ch = 0; ch < CFG_PWM_CHANNELS; ch++) {
        CHECK_EQ(fake_pwm[ch], 0);
    }
}

static void test_every_output_is_clamped_to_the_duty_ceiling(void)
{
    setup();
    CHECK_EQ(CFG_MAX_DUTY_PM, 8000);
    sma_request(0, 10000);
    sma_request(1, 7999);
    tick();
    CHECK_EQ(fake_pwm[0], 8000);
    CHECK_EQ(sma_duty(0), 8000);
    CHECK_EQ(fake_pwm[1], 7999);
    CHECK_EQ(sma_take_clamped(), 1);
    CHECK_EQ(sma_take_clamped(), 0);
    CHECK_EQ(sma_clamp(65535u), 8000);
}

static void test_actuators_drive_their_configured_channels(void)
{
    static const uint8_t channel[CFG_N_ACTUATORS] = CFG_ACTUATOR_CHANNELS;
    uint8_t a;
    setup();
    for (a = 0; a < CFG_N_ACTUATORS; a++) {
        sma_request(a, (uint16_t)(1000u + a));
    }
    tick();
    for (a = 0; a < CFG_N_ACTUATORS; a++) {
        CHECK_EQ(fake_pwm[channel[a]], 1000u + a);
    }
}

/* Ticks channel 0 at `duty` until it goes off; returns the real on-time (µs). */
static uint32_t on_time_until_cut(uint16_t duty, uint32_t period_us, uint8_t *hit)
{
    uint32_t on = 0;
    int guard = 0;
    sma_request(0, duty);
    *hit = tick_us(period_us);
    while (fake_pwm[0] != 0u && guard++ < 100000) {
        *hit = tick_us(period_us);
        on += period_us;
    }
    return on;
}

static void test_max_on_time_cuts_at_max_on_then_cools_for_min_cooldown(void)
{
    uint8_t hit;
    uint32_t off = 0;
    setup();
    CHECK_EQ(on_time_until_cut(6000, CFG_TICK_US, &hit), MAX_ON_US);
    CHECK_EQ(hit, 1);
    CHECK(sma_cooling(0));
    while (fake_pwm[0] == 0u && off < 10u * COOL_US) {
        tick();
        off += CFG_TICK_US;
    }
    CHECK(off >= COOL_US);                      /* cooled at least min_cooldown */
    CHECK(off <= COOL_US + 3u * CFG_TICK_US);   /* and heats again soon after */
    CHECK_EQ(fake_pwm[0], 6000);
}

static void test_on_time_runs_on_real_time_when_ticks_are_slow_or_fast(void)
{
    static const uint32_t periods[] = {250u, 1000u, 1760u, 3000u, 7000u};
    uint8_t hit;
    unsigned k;
    for (k = 0; k < sizeof periods / sizeof periods[0]; k++) {
        uint32_t on;
        setup();
        on = on_time_until_cut(6000, periods[k], &hit);
        /* The cut assumes the nominal tick: never late by more than one real tick. */
        CHECK(on <= MAX_ON_US + periods[k]);
        CHECK(on + 2u * periods[k] + CFG_TICK_US > MAX_ON_US);
    }
}

static void test_the_budget_is_right_across_the_microsecond_clock_wrap(void)
{
    uint8_t hit;
    setup_at(0xFFFFFFFFull - 20000u); /* wraps 20 ms into the on-period */
    CHECK_EQ(on_time_until_cut(6000, CFG_TICK_US, &hit), MAX_ON_US);
    CHECK_EQ(hit, 1);
    CHECK((uint32_t)fake_now_us < 100000u); /* it did wrap */
}

static void test_a_clock_that_steps_back_and_forth_never_lengthens_an_on_period(void)
{
    /* The STM32 bug of issue 11: +1 ms on one read, back on the next. */
    uint32_t true_on = 0;
    int k = 0;
    setup();
    sma_request(0, 6000);
    tick();
    while (fake_pwm[0] != 0u && k < 1000) {
        if (k % 2 == 0) {
            fake_now_us += 2000u; /* one real ms, read as two */
        } else {
            fake_now_us += 0u;    /* one real ms, read as none (back to the truth) */
        }
        sma_tick(0);
        true_on += 1000u;
        k++;
    }
    CHECK(true_on <= MAX_ON_US);
}

static void test_stop_and_start_between_two_ticks_continue_the_on_period(void)
{
    uint32_t on = 0;
    uint8_t hits = 0;
    setup();
    sma_request(0, 6000);
    tick();
    while (fake_pwm[0] != 0u && on < 10u * MAX_ON_US) {
        sma_all_off();          /* STOP ... */
        CHECK_EQ(fake_pwm[0], 0);
        sma_request(0, 6000);   /* ... and START before the next tick */
        hits = (uint8_t)(hits + tick());
        on += CFG_TICK_US;
    }
    CHECK(on <= MAX_ON_US);
    CHECK_EQ(hits, 1); /* one on-limit hit, on channel 0 */
}

static void test_estop_and_clear_refund_nothing(void)
{
    uint32_t t;
    setup();
    sma_request(0, 6000);
    for (t = 0; t < 30; t++) {
        tick();
    }
    sma_estop();
    sma_clear_estop();
    sma_request(0, 6000);
    for (t = 0; t < 20; t++) {
        CHECK_EQ(tick(), 0);
        CHECK_EQ(fake_pwm[0], 6000);
    }
    CHECK_EQ(tick(), 1); /* 50 ms of on-time in all, ESTOP or not */
    CHECK_EQ(fake_pwm[0], 0);
}

/* Drive channel 0 until the budget cuts it; returns the real on-time (µs). */
static uint32_t burst(void)
{
    uint32_t on = 0;
    sma_request(0, 6000);
    while (tick() == 0 && on < 10u * MAX_ON_US) {
        on += CFG_TICK_US;
    }
    return on;
}

static void test_any_on_period_owes_a_cool_down_in_proportion_to_it(void)
{
    uint32_t t, second;
    setup();
    sma_request(0, 6000);
    for (t = 0; t < 26; t++) { /* 25 ms on (the first tick only switches on) */
        tick();
    }
    sma_request(0, 0); /* one off tick, as a host sending STOP ... START */
    tick();
    CHECK_EQ(fake_pwm[0], 0);
    CHECK_EQ(sma_debt_us(0), 26000u); /* 26 ms on: the off tick is paid at the next tick */
    second = burst(); /* the off ms pays back only its share, 50 / 20 ms */
    CHECK(second >= MAX_ON_US - 26000u + 1500u && second <= MAX_ON_US - 26000u + 3500u);
    CHECK(sma_cooling(0));
}

static void test_a_cool_down_in_proportion_pays_the_on_time_back(void)
{
    uint32_t t, full;
    setup();
    sma_request(0, 6000);
    for (t = 0; t < 26; t++) {
        tick();
    }
    sma_request(0, 2500); /* holding is cooling */
    for (t = 0; t < 12; t++) { /* 26 ms × 20 / 50 = 10.4 ms, paid from the 2nd hold tick on */
        tick();
        CHECK_EQ(fake_pwm[0], 2500);
    }
    CHECK_EQ(sma_debt_us(0), 0);
    full = burst();
    CHECK(full >= MAX_ON_US - CFG_TICK_US && full <= MAX_ON_US);
}

static void test_after_an_on_limit_hit_the_coil_is_fully_off_for_its_cool_down(void)
{
    uint8_t hit;
    uint32_t off = 0;
    setup();
    on_time_until_cut(6000, CFG_TICK_US, &hit);
    sma_request(0, 2500);
    while (off < COOL_US - CFG_TICK_US) {
        tick();
        CHECK_EQ(fake_pwm[0], 0);
        off += CFG_TICK_US;
    }
    tick();
    tick();
    CHECK_EQ(fake_pwm[0], 2500);
}

static void test_holding_at_or_below_the_hold_ceiling_is_never_on_time(void)
{
    uint32_t t;
    setup();
    sma_request(0, CFG_HOLD_MAX_DUTY_PM);
    for (t = 0; t < 120000u; t++) { /* two minutes */
        CHECK_EQ(tick(), 0);
        CHECK_EQ(fake_pwm[0], CFG_HOLD_MAX_DUTY_PM);
    }
    CHECK_EQ(sma_debt_us(0), 0);
}

/* Bursts as long as the budget allows, at the full duty: the mean over every window of
 * CFG_DUTY_WINDOW_MS stays at or below CFG_MEAN_DUTY_PM (brute-force sliding sum). */
/* The step guard credits a coil with progress only if it heats above the hold ceiling on
 * the way to a target (safety.h): from the duty it is given, not the one it carried (a STOP
 * + START between two ticks must not credit the pre-STOP heating), holding is not heating,
 * and taking the record clears it. */
static void test_heated_names_the_coils_driven_above_the_hold_ceiling_since_it_was_taken(void)
{
    setup();
    (void)sma_take_heated();
    sma_request(0, CFG_HOLD_MAX_DUTY_PM);
    sma_request(1, CFG_HOLD_MAX_DUTY_PM + 1u);
    tick();
    CHECK_EQ(sma_take_heated(), 0x02);
    CHECK_EQ(sma_take_heated(), 0);
    sma_request(1, 0); /* a STOP: the tick after charges its on-time, but it no longer heats */
    tick();
    CHECK_EQ(sma_take_heated(), 0);
}

static void test_mean_duty_over_any_window_stays_below_the_limit(void)
{
    enum { W = CFG_DUTY_WINDOW_MS * 1000UL / CFG_TICK_US };
    static uint16_t hist[W];
    uint64_t sum = 0, on = 0;
    uint32_t t;
    setup();
    memset(hist, 0, sizeof hist);
    sma_request(0, 8000);
    for (t = 0; t < 5u * W; t++) {
        tick();
        sum += fake_pwm[0];
        on += fake_pwm[0];
        sum -= hist[t % W];
        hist[t % W] = fake_pwm[0];
        CHECK(sum <= (uint64_t)CFG_MEAN_DUTY_PM * W);
    }
    CHECK(on > (uint64_t)CFG_MEAN_DUTY_PM * 4u * W); /* and it does use its budget */
}

/* A held target whose limb never reaches its hold edge: its coil asks for the drive duty
 * tick after tick. Without a gait holding, the window only refuses it (no hit); while a
 * reached target is held, the first refused tick of each block is a hit (docs/safety.md). */
static void test_the_window_refusing_a_held_coil_is_a_hit_and_otherwise_not(void)
{
    enum { W = CFG_DUTY_WINDOW_MS * 1000UL / CFG_TICK_US };
    uint8_t holding;
    for (holding = 0; holding < 2u; holding++) {
        uint32_t t, blocks = 0, hits = 0, max_on_hits = 0;
        uint8_t was_blocked = 0;
        setup();
        sma_request(0, 8000);
        for (t = 0; t < 3u * W; t++) {
            uint8_t h;
            fake_now_us += CFG_TICK_US;
            h = sma_tick(holding);
            if (sma_cooling(0) && !was_blocked && fake_pwm[0] == 0u && sma_debt_us(0) < MAX_ON_US) {
                blocks++; /* off with the debt below max_on: the window, not the on-time */
            }
            was_blocked = (uint8_t)(sma_cooling(0) && sma_debt_us(0) < MAX_ON_US);
            hits += h & 1u;
            if ((h & 1u) && sma_debt_us(0) + CFG_TICK_US > MAX_ON_US) {
                max_on_hits++;
            }
        }
        CHECK(blocks > 0u); /* the window does refuse it (else this proves nothing) */
        if (holding) {
            CHECK(hits > max_on_hits);
        } else {
            CHECK_EQ(hits, max_on_hits);
        }
    }
}

static void test_run_time_limits_may_narrow_but_never_widen_the_envelope(void)
{
    uint8_t hit;
    setup();
    CHECK(sma_set_limits(8001, CFG_MAX_ON_TICKS, CFG_MIN_COOLDOWN_TICKS) != 0);
    CHECK(sma_set_limits(8000, CFG_MAX_ON_TICKS + 1u, CFG_MIN_COOLDOWN_TICKS) != 0);
    CHECK(sma_set_limits(8000, CFG_MAX_ON_TICKS, CFG_MIN_COOLDOWN_TICKS - 1u) != 0);
    CHECK_EQ(sma_max_duty(), 8000);
    /* a cool-down of 256 on-times would pay back nothing (refill 1/256 steps): refused */
    CHECK(CFG_MIN_COOLDOWN_TICKS <= 255u);
    CHECK_EQ(sma_set_limits(5000, 1, 256), -2);
    CHECK_EQ(sma_max_duty(), 8000);
    CHECK_EQ(sma_set_limits(5000, 1, 255), 0);
    CHECK_EQ(sma_set_limits(8000, CFG_MAX_ON_TICKS, CFG_MIN_COOLDOWN_TICKS), 0);
    CHECK_EQ(sma_set_limits(5000, 10, CFG_MIN_COOLDOWN_TICKS + 5u), 0);
    CHECK_EQ(sma_max_duty(), 5000);
    CHECK_EQ(on_time_until_cut(6000, CFG_TICK_US, &hit), 10u * CFG_TICK_US);
    setup();
    sma_set_limits(5000, 10, CFG_MIN_COOLDOWN_TICKS);
    sma_request(0, 6000);
    tick();
    CHECK_EQ(fake_pwm[0], 5000);
}

static void test_estop_turns_every_mosfet_off_within_one_tick(void)
{
    uint8_t ch;
    int t;
    setup();
    sma_request(0, 6000);
    sma_request(1, 6000);
    tick();
    CHECK_EQ(fake_pwm[0], 6000);
    sma_estop(); /* no tick in between: off when the call returns */
    for (ch = 0; ch < CFG_PWM_CHANNELS; ch++) {
        CHECK_EQ(fake_pwm[ch], 0);
    }
    for (t = 0; t < 100; t++) { /* latched: requests are ignored */
        sma_request(0, 6000);
        sma_request(1, 6000);
        tick();
        CHECK_EQ(fake_pwm[0], 0);
        CHECK_EQ(fake_pwm[1], 0);
    }
    CHECK(sma_estopped());
    sma_clear_estop();
    sma_request(0, 2000);
    tick();
    CHECK_EQ(fake_pwm[0], 2000);
}

static void test_all_off_turns_every_board_channel_off_at_once(void)
{
    uint8_t ch;
    setup();
    sma_request(0, 6000);
    sma_request(1, 6000);
    tick();
    for (ch = 0; ch < CFG_PWM_CHANNELS; ch++) {
        fake_pwm[ch] = 0x5555u; /* whatever a channel had */
    }
    sma_all_off();
    for (ch = 0; ch < CFG_PWM_CHANNELS; ch++) {
        CHECK_EQ(fake_pwm[ch], 0);
    }
    CHECK(!sma_estopped());
}

/* A reset that is not a power-on (sma_init(1)) keeps what the last run spent: a coil cut at
 * max_on stays off for its whole cool-down, whenever the reset came (docs/safety.md, "A reset"). */
static void test_a_warm_reset_keeps_the_cool_down_a_cold_one_forgets(void)
{
    uint8_t hit, warm;
    for (warm = 0; warm < 2; warm++) {
        uint32_t off = 0;
        setup();
        on_time_until_cut(6000, CFG_TICK_US, &hit);
        tick_us(COOL_US / 4u);      /* a quarter of the cool-down paid, then the reset */
        fake_now_us = 12345u;       /* the chip's clock starts over */
        sma_init(warm);
        CHECK_EQ(fake_pwm[0], 0);   /* every pin off at once, either way */
        CHECK_EQ(sma_cooling(0), warm);
        sma_request(0, 6000);
        while (fake_pwm[0] == 0u && off < 10u * COOL_US) {
            tick();
            off += CFG_TICK_US;
        }
        if (warm) {
            CHECK(off + CFG_TICK_US >= COOL_US * 3u / 4u); /* the rest of the cool-down, reset time not counted */
            CHECK(off <= COOL_US);
        } else {
            CHECK_EQ(off, CFG_TICK_US); /* cold: heats at the first tick */
        }
    }
}

/* The mean-duty window too: a coil that spent its window before the reset gets nothing more
 * until the window lets it, as if there had been no reset. */
static void test_a_warm_reset_keeps_the_mean_duty_window(void)
{
    enum { W = CFG_DUTY_WINDOW_MS * 1000UL / CFG_TICK_US };
    static uint16_t hist[W];
    uint64_t sum = 0;
    uint32_t t;
    setup();
    memset(hist, 0, sizeof hist);
    sma_request(0, 8000);
    for (t = 0; t < 3u * W; t++) {
        if (t % (W / 3u) == W / 6u) {
            sma_init(1);               /* resets, every third of a window */
            sma_request(0, 8000);
        }
        tick();
        sum += fake_pwm[0];
        sum -= hist[t % W];
        hist[t % W] = fake_pwm[0];
        CHECK(sum <= (uint64_t)CFG_MEAN_DUTY_PM * W + 8000u);
    }
}

/* An E-stop latched before a reset that is not a power-on stays latched (CLEAR releases it);
 * a power-on starts without one. */
static void test_an_estop_survives_a_warm_reset_not_a_power_on(void)
{
    setup();
    sma_estop();
    sma_init(1);
    CHECK(sma_estopped());
    sma_request(0, 6000);
    tick();
    CHECK_EQ(fake_pwm[0], 0);
    sma_clear_estop();
    sma_request(0, 6000);
    tick();
    CHECK_EQ(fake_pwm[0], 6000);
    sma_estop();
    sma_init(0);
    CHECK(!sma_estopped());
}

int main(void)
{
    RUN(test_init_turns_every_board_channel_off);
    RUN(test_heated_names_the_coils_driven_above_the_hold_ceiling_since_it_was_taken);
    RUN(test_every_output_is_clamped_to_the_duty_ceiling);
    RUN(test_actuators_drive_their_configured_channels);
    RUN(test_max_on_time_cuts_at_max_on_then_cools_for_min_cooldown);
    RUN(test_on_time_runs_on_real_time_when_ticks_are_slow_or_fast);
    RUN(test_the_budget_is_right_across_the_microsecond_clock_wrap);
    RUN(test_a_clock_that_steps_back_and_forth_never_lengthens_an_on_period);
    RUN(test_stop_and_start_between_two_ticks_continue_the_on_period);
    RUN(test_estop_and_clear_refund_nothing);
    RUN(test_any_on_period_owes_a_cool_down_in_proportion_to_it);
    RUN(test_a_cool_down_in_proportion_pays_the_on_time_back);
    RUN(test_after_an_on_limit_hit_the_coil_is_fully_off_for_its_cool_down);
    RUN(test_holding_at_or_below_the_hold_ceiling_is_never_on_time);
    RUN(test_mean_duty_over_any_window_stays_below_the_limit);
    RUN(test_the_window_refusing_a_held_coil_is_a_hit_and_otherwise_not);
    RUN(test_run_time_limits_may_narrow_but_never_widen_the_envelope);
    RUN(test_estop_turns_every_mosfet_off_within_one_tick);
    RUN(test_all_off_turns_every_board_channel_off_at_once);
    RUN(test_a_warm_reset_keeps_the_cool_down_a_cold_one_forgets);
    RUN(test_a_warm_reset_keeps_the_mean_duty_window);
    RUN(test_an_estop_survives_a_warm_reset_not_a_power_on);
    return UNIT_EXIT();
}
