/* Host unit tests of what core/sma.c trusts of the RAM it keeps across a reset that is not a
 * power-on (docs/safety.md, "A reset"): sma_init(1) keeps `kept` only when it carries this
 * build's mark and a window position in range; anything else is RAM this build did not leave
 * (noise after a power-on that optiboot reports as UNKNOWN, another image's state) and starts
 * cold. sma.c is included, not linked, so the tests can write that RAM as a reset finds it.
 * Configs: r1-fast (max_on 50 ms, 1 kHz) and r1-heat (the heat ceiling built in). */
#include <string.h>

#include "fake_hal.h"
#include "sma.c"
#include "unit.h"

static void tick(void)
{
    fake_now_us += CFG_TICK_US;
    (void)sma_tick(0);
}

/* A coil driven above the hold ceiling until the envelope cuts it: it owes its cool-down. */
static void spend(void)
{
    int guard = 0;
    fake_hal_reset();
    fake_now_us = 0;
    (void)sma_init(0);
    sma_request(0, 6000);
    tick();
    while (fake_pwm[0] != 0u && guard++ < 100000) {
        tick();
    }
    CHECK(sma_cooling(0));
    CHECK(sma_debt_us(0) > 0u);
}

/* The first tick after the reset heats the coil asked for: it started cold. */
static uint8_t heats_at_once(void)
{
    sma_request(0, 6000);
    tick();
    return (uint8_t)(fake_pwm[0] != 0u);
}

static void test_the_same_builds_ram_is_kept(void)
{
    spend();
    fake_now_us = 0;
    CHECK_EQ(sma_init(1), 1);
    CHECK(sma_cooling(0));
    CHECK(!heats_at_once());
}

static void test_ram_without_this_builds_mark_starts_cold(void)
{
    uint16_t other[] = {(uint16_t)(SMA_KEPT_MARK ^ 1u), (uint16_t)(SMA_KEPT_MARK ^ 0x8000u), 0u, 0xFFFFu};
    uint8_t k;
    for (k = 0; k < sizeof other / sizeof other[0]; k++) {
        if (other[k] == SMA_KEPT_MARK) {
            continue;
        }
        spend();
        kept.mark = other[k]; /* another image's RAM, or noise */
        fake_now_us = 0;
        CHECK_EQ(sma_init(1), 0);
        CHECK_EQ(sma_debt_us(0), 0);
        CHECK(!sma_cooling(0));
        CHECK(heats_at_once());
        CHECK_EQ(kept.mark, SMA_KEPT_MARK); /* and marked for the next reset */
    }
}

static void test_a_window_position_out_of_range_starts_cold(void)
{
    uint8_t slots[] = {SMA_WIN_SLOTS, SMA_WIN_SLOTS + 1u, 0x80u, 0xFFu};
    uint8_t k;
    for (k = 0; k < sizeof slots; k++) {
        spend();
        kept.slot = slots[k]; /* would index past the window */
        fake_now_us = 0;
        CHECK_EQ(sma_init(1), 0);
        CHECK_EQ(kept.slot, 0);
        CHECK(heats_at_once());
    }
}

static void test_a_power_on_starts_cold_whatever_the_ram_holds(void)
{
    spend();
    fake_now_us = 0;
    CHECK_EQ(sma_init(0), 0);
    CHECK(heats_at_once());
}

#ifdef CFG_COIL_TAU_MS
/* Noise that carries the mark: a heat outside 0 .. 100 % is taken as hot as can be, so the coil
 * gets at most the mean-duty ceiling (a negative heat would be colder than a cold start). */
static void test_a_heat_out_of_range_is_taken_as_hot_as_can_be(void)
{
    int32_t heats[] = {-1, INT32_MIN, (int32_t)(10000L << 8) + 1, INT32_MAX};
    uint8_t k;
    for (k = 0; k < sizeof heats / sizeof heats[0]; k++) {
        fake_hal_reset();
        fake_now_us = 0;
        (void)sma_init(0);
        kept.acts[0].heat = heats[k];
        CHECK_EQ(sma_init(1), 1);
        CHECK(kept.acts[0].heat >= 0 && kept.acts[0].heat <= (int32_t)(10000L << 8));
        sma_request(0, 6000);
        tick();
        CHECK(fake_pwm[0] <= CFG_MEAN_DUTY_PM);
    }
}
#endif

int main(void)
{
    RUN(test_the_same_builds_ram_is_kept);
    RUN(test_ram_without_this_builds_mark_starts_cold);
    RUN(test_a_window_position_out_of_range_starts_cold);
    RUN(test_a_power_on_starts_cold_whatever_the_ram_holds);
#ifdef CFG_COIL_TAU_MS
    RUN(test_a_heat_out_of_range_is_taken_as_hot_as_can_be);
#endif
    return UNIT_EXIT();
}
