/* Host unit tests of core/stall.c, the watches on each limb's step, called directly (their
 * rules in ctl.h; through ctl_demand they are tested in test_ctl*.c). Config: two limbs,
 * ψ* = 20°, band 19..21°, hold margin 1°. Built twice: against r1-fast (the reach watch) and
 * r1-stroke (full strokes: the lag watch, and the fall watch of SEQ_CLOCK_PAUSE). */
#include "ctl_unit.h"
#include "stall.h"
#include "unit.h"

/* Samples the smoothed ψ (1/16 of each new sample, psi.h) takes to settle on a jump. */
#define SMOOTH_SAMPLES 200u

/* Limb `limb` at ψ = `deg` for `n` samples: its smoothed ψ settles there. */
static void stay(uint8_t limb, double deg, uint32_t n)
{
    uint32_t k;
    for (k = 0; k < n; k++) {
        put(limb, deg);
    }
}

/* One look of the reach watch at limb 0 (it looks when ctl_look is 0). */
static uint8_t reach_look(void)
{
    ctl_look = 0;
    return stall_at_reach(0, &ctl_limb[0]);
}

static void test_a_new_target_starts_a_fresh_step(void)
{
    ctl_limb_t *c = &ctl_limb[0];
    setup();
    put(0, 10.0);
    stall_watch(0, 1, psi_level(0), 1, 1000);
    c->stall = CTL_STALL_UNREACHABLE;
    c->crossings = 2;
    c->heat = 1;
    c->still = 3;
    stall_watch(0, 1, psi_level(0), 1, 1000); /* the same step: decided, kept */
    CHECK_EQ(ctl_stall(0), CTL_STALL_UNREACHABLE);
    CHECK_EQ(c->crossings, 2);
    stall_watch(0, 0, psi_level(0), 0, 0); /* another target: forgotten */
    CHECK_EQ(c->target, 0);
    CHECK_EQ(ctl_stall(0), CTL_STALL_NONE);
    CHECK_EQ(c->crossings, 0);
    CHECK_EQ(c->heat, 0);
    CHECK_EQ(c->best, PSI_FAR);
    CHECK_EQ(c->still, NOT_SEEN);
}

static void test_the_third_level_change_of_a_step_makes_it_oscillate(void)
{
    setup();
    put(0, 10.0);
    stall_watch(0, 1, psi_level(0), 1, 1100); /* the first level: no crossing */
    put(0, 21.5);                             /* up: level 1, inside the margin */
    stall_watch(0, 1, psi_level(0), 0, 0);
    put(0, 18.5); /* back down below the band */
    stall_watch(0, 1, psi_level(0), 1, 300);
    CHECK_EQ(ctl_limb[0].crossings, 2);
    CHECK_EQ(ctl_stall(0), CTL_STALL_NONE);
    put(0, 21.5);
    stall_watch(0, 1, psi_level(0), 0, 0);
    CHECK_EQ(ctl_limb[0].crossings, CTL_OSC_CROSSINGS);
    CHECK_EQ(ctl_stall(0), CTL_STALL_OSCILLATING);
    put(0, 21.5);
    CHECK_EQ(psi_settled(0), 1); /* relaxed: above the band's upper edge is enough */
}

static void test_a_limb_unsettled_at_its_level_for_a_hover_time_oscillates(void)
{
    uint32_t k;
    setup();
    put(0, 21.5); /* level 1, inside the margin: not settled */
    for (k = 0; k < TICKS(CTL_HOVER_MS); k++) {
        stall_watch(0, 1, psi_level(0), 0, 0);
    }
    CHECK_EQ(ctl_stall(0), CTL_STALL_NONE);
    stall_watch(0, 1, psi_level(0), 0, 0);
    CHECK_EQ(ctl_stall(0), CTL_STALL_OSCILLATING);
    setup();
    put(0, 10.0); /* settled at its level: never hovering */
    for (k = 0; k < 2u * TICKS(CTL_HOVER_MS); k++) {
        stall_watch(0, 0, psi_level(0), 0, 0);
    }
    CHECK_EQ(ctl_stall(0), CTL_STALL_NONE);
}

static void test_heating_without_progress_for_the_stall_time_cannot_reach(void)
{
    uint32_t k;
    setup();
    put(0, 5.0);
    stall_watch(0, 1, psi_level(0), 1, 1500); /* the step's first progress edge */
    for (k = 1; k < TICKS(CTL_STALL_MS) / 2u; k++) {
        stall_watch(0, 1, psi_level(0), 1, 1500);
    }
    stall_watch(0, 1, psi_level(0), 1, 1200); /* one edge closer: the clock restarts */
    for (k = 1; k < TICKS(CTL_STALL_MS); k++) {
        stall_watch(0, 1, psi_level(0), 1, 1500); /* a worse edge (noise) is no progress */
    }
    CHECK_EQ(ctl_stall(0), CTL_STALL_NONE);
#ifdef CFG_LIMB_STROKE_CDEG
    CHECK_EQ(ctl_limb[0].lagged, 1); /* CTL_LAG_MS without progress: not waited for */
#endif
    stall_watch(0, 1, psi_level(0), 1, 1200);
    CHECK_EQ(ctl_stall(0), CTL_STALL_UNREACHABLE);
    setup();
    put(0, 5.0);
    for (k = 0; k < 2u * TICKS(CTL_STALL_MS); k++) {
        stall_watch(0, 1, psi_level(0), 0, 1500); /* not heating (waiting): no clock */
    }
    CHECK_EQ(ctl_stall(0), CTL_STALL_NONE);
}

static void test_the_reach_watch_stops_a_rise_that_stopped_after_its_reach_time(void)
{
    uint32_t k;
    setup();
    ctl_limb[0].still = NOT_SEEN; /* as a new step leaves it */
    stay(0, 8.0, SMOOTH_SAMPLES);
    CHECK_EQ(reach_look(), 0); /* its lowest */
    stay(0, 16.0, SMOOTH_SAMPLES);
    CHECK_EQ(reach_look(), 0); /* 8° up: a new high */
    for (k = 1; k < REACH_LOOKS; k++) {
        put(0, 16.0);
        CHECK_EQ(reach_look(), 0);
        ctl_look = 1; /* looks only once in CTL_REACH_EVERY ticks: this one does not count */
        CHECK_EQ(stall_at_reach(0, &ctl_limb[0]), 0);
    }
    CHECK_EQ(reach_look(), 1); /* REACH_LOOKS looks without a gain */
    CHECK_EQ(reach_look(), 1);
    /* a rise of less than CTL_MOVE_CDEG that stops is not the reach watch's */
    setup();
    ctl_limb[0].still = NOT_SEEN;
    stay(0, 8.0, SMOOTH_SAMPLES);
    reach_look();
    stay(0, 11.0, SMOOTH_SAMPLES);
    for (k = 0; k < 3u * REACH_LOOKS; k++) {
        CHECK_EQ(reach_look(), 0);
    }
}

#if SEQ_CLOCK_PAUSE
/* Both limbs from 30° (level 1) to target 0: the step starts there, as ctl_demand starts it. */
static void fall_from_30(uint8_t target[CFG_N_LIMBS])
{
    uint8_t i;
    setup();
    for (i = 0; i < CFG_N_LIMBS; i++) {
        stay(i, 30.0, SMOOTH_SAMPLES);
        target[i] = 0;
        stall_watch(i, 0, psi_level(i), 0, psi_to_go_cdeg(i, 0, 0));
    }
}

static void test_the_fall_watch_says_down_while_every_falling_limb_comes_down(void)
{
    uint8_t target[CFG_N_LIMBS];
    uint32_t k, down = 0, looks = 0;
    double deg = 30.0;
    fall_from_30(target);
    CHECK_EQ(stall_fall_watch(target), STUCK); /* no drop yet */
    for (k = 1; k <= 400u; k++) {             /* 1° every 40 samples (25°/s at 1 kHz) */
        if (k % 40u == 0u) {
            deg -= 1.0;
        }
        put(0, deg);
        put(1, deg);
        if (k % CTL_REACH_EVERY == 0u) {
            down += stall_fall_watch(target) == DOWN;
            looks++;
        }
    }
    CHECK(down + 8u >= looks); /* from its first degree down (the smoothed ψ lags) */
    for (k = 0; k < 2u * TICKS(CTL_FALL_PROGRESS_MS) && stall_fall_watch(target) == DOWN; k += CTL_REACH_EVERY) {
        stay(0, deg, CTL_REACH_EVERY); /* they stop */
        stay(1, deg, CTL_REACH_EVERY);
    }
    CHECK_EQ(stall_fall_watch(target), STUCK);
    CHECK(k >= TICKS(CTL_FALL_PROGRESS_MS) - SMOOTH_SAMPLES);
    CHECK(k <= TICKS(CTL_FALL_PROGRESS_MS) + SMOOTH_SAMPLES);
    stay(0, 5.0, SMOOTH_SAMPLES); /* both down and settled: done */
    stay(1, 5.0, SMOOTH_SAMPLES);
    CHECK_EQ(stall_fall_watch(target), DONE);
    target[0] = 1; /* a limb rising: its step's time runs */
    CHECK_EQ(stall_fall_watch(target), STUCK);
}
#endif

int main(void)
{
    RUN(test_a_new_target_starts_a_fresh_step);
    RUN(test_the_third_level_change_of_a_step_makes_it_oscillate);
    RUN(test_a_limb_unsettled_at_its_level_for_a_hover_time_oscillates);
    RUN(test_heating_without_progress_for_the_stall_time_cannot_reach);
    RUN(test_the_reach_watch_stops_a_rise_that_stopped_after_its_reach_time);
#if SEQ_CLOCK_PAUSE
    RUN(test_the_fall_watch_says_down_while_every_falling_limb_comes_down);
#endif
    return UNIT_EXIT();
}
