/* Host unit tests of full strokes in core/psi.c and core/ctl.c ([[limb]] stroke_deg).
 * Config: two limbs, ψ* = 20°, band 19..21°, hold margin 1° (without a stroke: hold edge 22°,
 * top 23°); limb 0 ("left") with a stroke of 60°, limb 1 ("right") 50°, limb i driven by
 * actuator i; the rise lead is limb 0 (the larger stroke), the fall lead limb 1
 * (control.stroke_fall_lead). Shares of the climb from the band's upper edge 21°: limb 0
 * (ψ − 21) / 39, limb 1 (ψ − 21) / 29. */
#include "ctl_unit.h"
#include "unit.h"

#define HOVER_TICKS ((uint32_t)CTL_HOVER_MS * CFG_TICK_HZ / 1000u)
/* A limb climbing to its stroke has stopped after this long without a 0.5° gain (ctl.h). */
#define STOP_TICKS ((uint32_t)CTL_CLIMB_STOP_MS * CFG_TICK_HZ / 1000u)
#define CLIMB_TICKS ((uint32_t)CTL_CLIMB_MAX_MS * CFG_TICK_HZ / 1000u)
#define LAG_TICKS ((uint32_t)CTL_LAG_MS * CFG_TICK_HZ / 1000u)
/* Samples the smoothed ψ (1/16 of each new sample, psi.h) takes to come within 1° of a jump of
 * up to 60°: 16 ln 60 ≈ 66. A climb is judged on it (stall.c, climbing). */
#define SMOOTH_TICKS 100u

/* Step 10 from 00 after `wait` ticks below the band: limb 0 goes up to `deg` (± `noise`, never
 * a climbing degree) and stays there until the controller relaxes it: stopped short,
 * CTL_CLIMB_STOP_MS after its smoothed ψ stopped gaining. */
static void stop_short_at(double deg, double noise, uint32_t wait)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint32_t k;
    setup();
    put(1, 0.0);
    put(0, 5.0);
    for (k = 0; k < wait; k++) {
        put(0, 5.0);
        demand(1, 0, duty);
    }
    for (k = 0; k <= STOP_TICKS + SMOOTH_TICKS && ctl_stall(0) == CTL_STALL_NONE; k++) {
        put(0, deg + noise * (double)(k % 2u));
        demand(1, 0, duty);
    }
    CHECK(k > STOP_TICKS); /* not before CTL_CLIMB_STOP_MS */
    CHECK_EQ(ctl_stall(0), CTL_STALL_OSCILLATING);
}

static void test_the_config_has_the_strokes(void)
{
    CHECK_EQ(psi_stroke_cdeg(0), 6000);
    CHECK_EQ(psi_stroke_cdeg(1), 5000);
    CHECK_EQ(CFG_HOLD_MARGIN_CDEG, 100);
    CHECK_EQ(CFG_STROKE_RISE_LEAD, 0);
    CHECK_EQ(CFG_STROKE_FALL_LEAD, 1);
}

static void test_a_raised_limb_is_held_at_its_stroke_not_past_its_band(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    put(1, 0.0);
    put(0, 30.0); /* level 1, far past the margin hold edge (22°), below the stroke */
    CHECK_EQ(psi_level(0), 1);
    CHECK(!psi_last_at_or_above_hold(0, 0));
    demand(1, 0, duty);
    CHECK_EQ(duty[0], DRIVE); /* climbs on */
    put(0, 59.9);
    demand(1, 0, duty);
    CHECK_EQ(duty[0], DRIVE);
    put(0, 60.5); /* between the stroke and the hold top (61°), going up: keeps heating */
    CHECK(psi_last_at_or_above_hold(0, 0));
    demand(1, 0, duty);
    CHECK_EQ(duty[0], DRIVE);
    put(0, 61.2); /* the hold top: off */
    CHECK(psi_last_at_or_above_hold_top(0, 0));
    demand(1, 0, duty);
    CHECK_EQ(duty[0], 0);
    put(0, 60.4); /* sagging, still above the stroke: off */
    demand(1, 0, duty);
    CHECK_EQ(duty[0], 0);
    put(0, 59.5); /* below the stroke: heat */
    demand(1, 0, duty);
    CHECK_EQ(duty[0], DRIVE);
}

static void test_a_limb_settles_on_its_top_level_only_at_its_stroke(void)
{
    setup();
    put(1, 0.0);
    put(0, 40.0);
    put(0, 40.0);
    CHECK_EQ(psi_level(0), 1);
    CHECK(!psi_settled(0)); /* level 1 but short of the stroke */
    put(0, 60.2);
    put(0, 60.2);
    CHECK(psi_settled(0));
    put(0, 45.0); /* settled stays latched inside the band's edges */
    CHECK(psi_settled(0));
}

static void test_the_settle_edge_below_the_band_keeps_the_margin(void)
{
    setup();
    put(0, 18.5); /* level 0, between the band's lower edge 19° and the settle edge 18° */
    put(0, 18.5);
    CHECK_EQ(psi_level(0), 0);
    CHECK(!psi_settled(0));
    put(0, 17.5);
    put(0, 17.5);
    CHECK(psi_settled(0));
}

static void test_moving_psi_star_past_the_stroke_gives_back_the_margin_hold(void)
{
    setup();
    CHECK_EQ(psi_set_band(1, 0, 5500, 200), 0); /* ψ* 55° > stroke 50°: hold edge 57° */
    put(1, 56.5);
    CHECK_EQ(psi_level(1), 1);
    CHECK(!psi_last_at_or_above_hold(1, 0));
    put(1, 57.2);
    CHECK(psi_last_at_or_above_hold(1, 0));
    CHECK(!psi_last_at_or_above_hold_top(1, 0));
    CHECK_EQ(psi_stroke_cdeg(1), PSI_NO_STROKE); /* for the controller's rules too */
    CHECK_EQ(psi_set_band(1, 0, 2000, 200), 0); /* back below the stroke: held at 50° again */
    CHECK_EQ(psi_stroke_cdeg(1), 5000);
    put(1, 45.0);
    CHECK(!psi_last_at_or_above_hold(1, 0));
    put(1, 50.2);
    CHECK(psi_last_at_or_above_hold(1, 0));
}

static void test_the_larger_stroke_crosses_first_and_the_others_wait_warm(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    put(0, 5.0);
    put(1, 10.0); /* nearer its crossing than limb 0: without strokes limb 0 would lead */
    demand(1, 1, duty);
    CHECK_EQ(duty[0], DRIVE);
    CHECK_EQ(duty[1], HOLD);
    put(0, 20.5); /* in the band: not crossed yet */
    demand(1, 1, duty);
    CHECK_EQ(duty[0], DRIVE);
    CHECK_EQ(duty[1], HOLD);
    put(0, 21.5); /* crossed (share 1 %): limb 1 goes; limb 0 is within 5 % of limb 1's 0 */
    demand(1, 1, duty);
    CHECK_EQ(psi_level(0), 1);
    CHECK_EQ(duty[1], DRIVE);
    CHECK_EQ(duty[0], DRIVE);
    put(0, 24.0); /* share 8 %: ahead of a limb that has not crossed: waits warm */
    demand(1, 1, duty);
    CHECK_EQ(duty[0], HOLD);
    CHECK_EQ(duty[1], DRIVE);
}

static void test_a_limb_waiting_for_a_larger_stroke_is_kept_warm_only_for_a_while(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint32_t k, warm = (uint32_t)CTL_SAG_WAIT_MS * CFG_TICK_HZ / 1000u;
    setup();
    put(0, 5.0); /* its coil dead, say: it never crosses */
    put(1, 5.0);
    for (k = 0; k < warm; k++) {
        demand(1, 1, duty);
        CHECK_EQ(duty[1], HOLD);
    }
    for (k = 0; k < 3u * warm; k++) {
        demand(1, 1, duty);
        CHECK_EQ(duty[1], 0); /* then off: no coil stays on because another cannot heat */
    }
    demand(0, 0, duty); /* a new step, and the next rise: warm again for a while */
    demand(1, 1, duty);
    CHECK_EQ(duty[1], HOLD);
    put(0, 21.5); /* limb 0 has crossed: limb 1 goes */
    demand(1, 1, duty);
    CHECK_EQ(duty[1], DRIVE);
}

static void test_a_limb_already_at_its_stroke_is_held_there_while_another_rises(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    put(0, 60.5); /* step 10: limb 0 at its stroke */
    put(0, 60.5);
    put(1, 5.0);
    demand(1, 0, duty);
    CHECK(psi_settled(0));
    put(0, 55.0); /* step 11: limb 1 rises; limb 0 sags (share 87 %, far ahead of limb 1's 0) */
    demand(1, 1, duty);
    CHECK_EQ(duty[0], DRIVE); /* its hold, not a wait: it is not climbing in this step */
    CHECK_EQ(duty[1], DRIVE);
}

static void test_limbs_climb_to_their_strokes_in_step(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    put(0, 5.0); /* the step begins with both below their bands */
    put(1, 5.0);
    demand(1, 1, duty);
    put(0, 40.0); /* share 49 % */
    put(1, 30.0); /* share 31 % */
    demand(1, 1, duty);
    CHECK_EQ(duty[0], HOLD);
    CHECK_EQ(duty[1], DRIVE);
    put(1, 35.0); /* 48 %: within 5 %, both climb */
    demand(1, 1, duty);
    CHECK_EQ(duty[0], DRIVE);
    CHECK_EQ(duty[1], DRIVE);
    put(1, 50.5); /* at its stroke, below its hold top: ahead of limb 0, it waits warm */
    demand(1, 1, duty);
    CHECK_EQ(duty[1], HOLD);
    CHECK_EQ(duty[0], DRIVE);
    put(1, 51.2); /* its hold top: off, and no longer in the climb; limb 0 climbs on alone */
    demand(1, 1, duty);
    CHECK_EQ(duty[1], 0);
    CHECK_EQ(duty[0], DRIVE);
}

static void test_a_limb_still_climbing_to_its_stroke_is_not_hovering(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint32_t k;
    double psi = 25.0;
    setup();
    put(1, 0.0);
    put(0, 5.0); /* the step begins below the band */
    demand(1, 0, duty);
    put(0, psi);
    for (k = 0; k < 8u * STOP_TICKS; k++) {
        if (k % (STOP_TICKS / 2u) == 0u) {
            psi += 0.75; /* 0.75° every half stop time: 10°/s */
            put(0, psi);
        }
        demand(1, 0, duty);
        CHECK_EQ(duty[0], DRIVE);
    }
    CHECK_EQ(ctl_stall(0), CTL_STALL_NONE);
    CHECK(!psi_settled(0));
}

static void test_a_limb_that_stops_climbing_short_of_its_stroke_settles_there(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    stop_short_at(35.0, 0.5, 1u); /* noise, no climb */
    put(0, 35.0);
    put(0, 35.0);
    CHECK(psi_settled(0)); /* relaxed: settled on the band's edges, the step can go on */
    put(0, 35.6);
    demand(1, 0, duty);
    /* a 30° jump, then nothing: the knee watch (CTL_KNEE_MS) found its coil through its
     * transformation, as the hover clock would have: held where it stopped, and in this step
     * kept at the hold duty (warm, never the drive duty) */
    CHECK_EQ(duty[0], HOLD);
    put(0, 33.5);
    demand(1, 0, duty);
    CHECK_EQ(duty[0], HOLD);
    put(1, 30.0);             /* the next step raises limb 1; limb 0 stays up */
    put(0, 35.6);
    demand(1, 1, duty);
    CHECK_EQ(duty[0], 0); /* held where it stopped (about 34.25..35.25°), not heated on towards 60° */
    put(0, 33.5);
    demand(1, 1, duty);
    CHECK_EQ(duty[0], DRIVE);
    put(0, 34.5); /* going up again inside the band: keeps heating */
    demand(1, 1, duty);
    CHECK_EQ(duty[0], DRIVE);
    put(0, 35.6);
    demand(1, 1, duty);
    CHECK_EQ(duty[0], 0);
    put(0, 15.0); /* down: the next time it is raised it climbs to its stroke again */
    put(0, 15.0);
    demand(0, 1, duty);
    put(0, 40.0);
    demand(1, 1, duty);
    CHECK_EQ(duty[0], DRIVE);
}

static void test_a_limb_relaxed_mid_climb_is_heated_on_while_it_still_climbs(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint32_t k;
    uint8_t j;
    double psi = 23.0;
    setup();
    put(1, 0.0);
    put(0, 5.0);
    demand(1, 0, duty); /* the step that raises it, from below */
    for (j = 0; j < 6u && ctl_stall(0) == CTL_STALL_NONE; j++) { /* in and out of its band (noise) */
        for (k = 0; k < 8u; k++) {
            put(0, j % 2u ? 18.0 : 23.0);
            demand(1, 0, duty);
        }
    }
    CHECK_EQ(ctl_stall(0), CTL_STALL_OSCILLATING); /* the crossings relaxed it, mid-climb */
    CHECK_EQ(psi_level(0), 1);
    for (k = 0; k < 3u * HOVER_TICKS; k++) { /* then climbs on at 2° a hover time */
        psi += 2.0 / (double)HOVER_TICKS;
        put(0, psi);
        demand(1, 0, duty);
        CHECK_EQ(duty[0], DRIVE);
    }
    for (k = 0; k < HOVER_TICKS + 2u * CTL_REACH_EVERY + SMOOTH_TICKS; k++) { /* and stops */
        put(0, psi);
        demand(1, 0, duty);
    }
    put(0, psi + 0.6);
    demand(1, 0, duty);
    CHECK_EQ(duty[0], 0); /* held where it stopped (within the last 1° it gained), 6° above where it was relaxed */
    put(0, psi - 3.0);
    demand(1, 0, duty);
    CHECK_EQ(duty[0], DRIVE);
}

static void test_a_climb_is_not_waited_for_longer_than_the_climb_limit(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint32_t k, n = CLIMB_TICKS + 2u * HOVER_TICKS;
    double psi = 21.5;
    setup();
    put(1, 0.0);
    put(0, 5.0);
    demand(1, 0, duty);
    for (k = 0; k < n; k++) {
        if (k % (HOVER_TICKS / 2u) == 0u) {
            psi += 0.8 * 1.25; /* 1° per 0.4 hover times: a slow climb that never gets there */
            put(0, psi);
        }
        demand(1, 0, duty);
    }
    CHECK(psi < 60.0);
    CHECK_EQ(ctl_stall(0), CTL_STALL_OSCILLATING);
}

static void test_a_limb_waiting_for_another_in_step_is_not_hovering(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint32_t k;
    setup();
    put(0, 5.0);
    put(1, 5.0);
    demand(1, 1, duty);
    put(0, 50.0); /* share 74 % */
    for (k = 0; k < 6u * STOP_TICKS; k++) {
        if (k % (STOP_TICKS / 2u) == 0u) {
            put(1, 25.0 + 0.75 * (double)(k / (STOP_TICKS / 2u))); /* climbing, 14..45 %: limb 0 waits */
        }
        demand(1, 1, duty);
        CHECK_EQ(duty[0], HOLD);
        CHECK_EQ(duty[1], DRIVE);
    }
    CHECK_EQ(ctl_stall(0), CTL_STALL_NONE);
    CHECK_EQ(ctl_stall(1), CTL_STALL_NONE);
}

static void test_a_limb_that_stops_just_past_its_band_is_held_at_the_hold_it_has_without_a_stroke(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    stop_short_at(21.5, 0.0, 1u); /* stops just past its band (upper edge 21°) */
    put(1, 30.0); /* the next step leaves limb 0 raised */
    put(0, 21.8);
    demand(1, 1, duty);
    CHECK_EQ(duty[0], DRIVE); /* below 22° (ψ* + h/2 + the 1° hold margin), not held at 20.5..21.5° */
    put(0, 22.5);
    demand(1, 1, duty);
    CHECK_EQ(duty[0], DRIVE);
    put(0, 23.1);
    demand(1, 1, duty);
    CHECK_EQ(duty[0], 0);
}

static void test_a_limb_that_reaches_its_top_level_late_is_held_where_it_stopped(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    stop_short_at(40.0, 0.0, CLIMB_TICKS + 100u); /* past the climb limit before it crosses */
    put(1, 30.0); /* the next step leaves it raised: held at 39..40° */
    put(0, 38.5);
    demand(1, 1, duty);
    CHECK_EQ(duty[0], DRIVE);
    put(0, 40.2);
    demand(1, 1, duty);
    CHECK_EQ(duty[0], 0);
}

static void test_climbing_in_step_waits_for_a_slow_limb_only_for_the_climb_limit(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint32_t k, limit = CLIMB_TICKS;
    setup();
    put(0, 5.0);
    put(1, 5.0);
    put(1, 20.5); /* in its band from below: level 0 */
    demand(1, 1, duty);
    put(0, 50.0); /* share 74 %: far ahead of limb 1 */
    for (k = 1; k < limit + 10u; k++) {
        put(0, 50.0);
        put(1, 20.5 + (double)k / 200.0); /* 5°/s from its band, far behind: never fast (no knee) */
        demand(1, 1, duty);
        if (k + 1u < limit) {
            CHECK_EQ(duty[0], HOLD);
        }
    }
    CHECK_EQ(duty[0], DRIVE); /* the climb limit has passed: limb 0 goes on to its stroke */
}

static void test_a_limb_that_stopped_short_caps_the_others_in_step(void)
{
    /* Step 11 from 00; both ends at 30°: limb 0 has covered 23 % of its climb, limb 1 31 %.
     * Limb 1 waits for limb 0 (5 % ahead); limb 0 stops there (a worn coil), told after a hover
     * time (CTL_CLIMB_STOP_MS only when no limb waits for it). Limb 1 then does
     * not climb on to its stroke: it is past where limb 0 stopped and gains nothing, waits at
     * the hold duty and counts as stopped (the strokes keep their order: ctl.h). */
    uint16_t duty[CFG_N_ACTUATORS];
    uint32_t k;
    setup();
    put(0, 5.0);
    put(1, 5.0);
    demand(1, 1, duty);
    for (k = 0; k <= HOVER_TICKS + SMOOTH_TICKS && ctl_stall(0) == CTL_STALL_NONE; k++) {
        put(0, 30.0);
        put(1, 30.0);
        demand(1, 1, duty);
        CHECK_EQ(duty[1], HOLD);
    }
    /* waited for, it is given a hover time by the clock; a 25° jump and then nothing is a coil
     * through its transformation, and the knee watch says so first (CTL_KNEE_MS) */
    CHECK(k < HOVER_TICKS);
    CHECK_EQ(ctl_stall(0), CTL_STALL_OSCILLATING); /* limb 0 stopped short */
    for (k = 0; k <= STOP_TICKS + 1u && ctl_stall(1) == CTL_STALL_NONE; k++) {
        put(0, 30.0);
        put(1, 30.0);
        demand(1, 1, duty);
        if (k > STOP_TICKS / 2u + 1u) {
            CHECK_EQ(duty[1], HOLD); /* gained nothing for half a stop time: not on to its 50° */
        }
    }
    CHECK_EQ(ctl_stall(1), CTL_STALL_OSCILLATING); /* stopped there: the step goes on */
}

static void test_a_limb_stopped_short_in_an_earlier_step_caps_nothing(void)
{
    /* Step 10: limb 0 stops short at 30° (a worn coil). Step 11 raises limb 1 alone: it climbs
     * to its 50° stroke, not held where limb 0 stopped a step ago (it stopped at 29°). */
    uint16_t duty[CFG_N_ACTUATORS];
    uint32_t k;
    double p1 = 22.0;
    setup();
    put(0, 5.0);
    put(1, 0.0);
    demand(1, 0, duty);
    for (k = 0; k < 600u && ctl_stall(0) == CTL_STALL_NONE; k++) {
        put(0, 30.0);
        put(1, 0.0);
        demand(1, 0, duty);
    }
    CHECK_EQ(ctl_stall(0), CTL_STALL_OSCILLATING);
    put(1, 5.0);
    demand(1, 1, duty);
    for (k = 0; k < 3000u && p1 < 50.0; k++) {
        put(0, 30.0);
        put(1, p1);
        demand(1, 1, duty);
        CHECK_EQ(duty[1], DRIVE);
        p1 += 0.02; /* 20°/s while driven */
    }
    CHECK(p1 >= 50.0);
}

static void test_falling_together_the_others_are_held_at_their_strokes_until_the_fall_lead_is_down(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint32_t k, wait = (uint32_t)CTL_FALL_WAIT_MS * CFG_TICK_HZ / 1000u;
    setup();
    put(0, 60.5);
    put(1, 50.5);
    demand(1, 1, duty);
    put(0, 59.5); /* both lowered: limb 1 (the fall lead) goes down, limb 0 is held at 60° */
    demand(0, 0, duty);
    CHECK_EQ(duty[1], 0);
    CHECK_EQ(duty[0], DRIVE);
    put(0, 60.2);
    demand(0, 0, duty);
    CHECK_EQ(duty[0], 0);
    put(0, 59.5);
    put(1, 40.0); /* the lead 65 % up its climb (21..50°): still held */
    demand(0, 0, duty);
    CHECK_EQ(duty[0], DRIVE);
    put(1, 34.0); /* 45 %: past halfway down, still on its top level: limb 0 goes down too */
    CHECK_EQ(psi_level(1), 1);
    demand(0, 0, duty);
    CHECK_EQ(duty[0], 0);
    put(0, 60.5); /* again, with a lead that never comes down: held for CTL_FALL_WAIT_MS at most */
    put(1, 50.5);
    put(1, 50.5);
    demand(1, 1, duty);
    put(0, 59.5);
    for (k = 0; k < wait; k++) {
        demand(0, 0, duty);
        CHECK_EQ(duty[0], DRIVE);
    }
    for (k = 0; k < 100u; k++) {
        demand(0, 0, duty);
        CHECK_EQ(duty[0], 0);
    }
}

/* Step 11 from 00, limb 0 across its band at 50° (share 74 %), limb 1 below its band from 10°
 * heated at the drive duty and gaining `step` degrees every `every` ticks; returns the tick at
 * which limb 0 stopped waiting warm (0: it waited throughout `n` ticks), or n + 1 if some tick
 * did not drive limb 1 or gave limb 0 neither the hold nor the drive duty. */
static uint32_t wait_for_a_lagging_limb(double step, uint32_t every, uint32_t n)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint32_t k;
    double psi1 = 10.0;
    setup();
    put(0, 5.0);
    put(1, psi1);
    demand(1, 1, duty);
    for (k = 1; k < n; k++) {
        if (k % every == 0u && psi1 + step < 19.0) {
            psi1 += step;
        }
        put(0, 50.0);
        put(1, psi1);
        demand(1, 1, duty);
        if (duty[1] != DRIVE || (duty[0] != HOLD && duty[0] != DRIVE)) {
            return n + 1u;
        }
        if (duty[0] == DRIVE) {
            return k;
        }
    }
    return 0;
}

static void test_climbing_in_step_waits_for_a_limb_only_while_it_still_rises(void)
{
    /* a coil that does not heat: its end stays where it is */
    uint32_t k = wait_for_a_lagging_limb(0.0, 1u, CLIMB_TICKS);
    CHECK(k >= LAG_TICKS);                /* not before the lag time */
    CHECK(k <= LAG_TICKS + 2u);           /* then at once, not at the climb limit */
    /* nor one whose end the other's warm coil lifts through the body, 1° per 0.8 s */
    k = wait_for_a_lagging_limb(1.0, LAG_TICKS * 4u / 5u, CLIMB_TICKS);
    CHECK(k >= LAG_TICKS);
    CHECK(k + LAG_TICKS / 2u < CLIMB_TICKS);
    /* a slow healthy rise, 1° every 0.2 s (5°/s), is waited for */
    CHECK_EQ(wait_for_a_lagging_limb(1.0, LAG_TICKS / 5u, LAG_TICKS + LAG_TICKS / 2u), 0u);
}

static void test_a_lagging_limb_given_up_is_not_waited_for_again_in_the_step(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint32_t k;
    setup();
    put(0, 5.0);
    put(1, 10.0);
    demand(1, 1, duty);
    for (k = 1; k <= LAG_TICKS + LAG_TICKS / 5u; k++) {
        put(0, 50.0);
        put(1, 10.0);
        demand(1, 1, duty);
    }
    CHECK_EQ(duty[0], DRIVE);
    for (k = 0; k < LAG_TICKS / 2u; k++) {
        put(0, 50.0);
        put(1, 10.0 + 8.0 * (double)k / (double)(LAG_TICKS / 2u)); /* lifted by limb 0's climb */
        demand(1, 1, duty);
        CHECK_EQ(duty[0], DRIVE);
    }
    demand(0, 0, duty); /* the next rise watches it afresh */
    put(0, 5.0);
    put(1, 10.0);
    demand(1, 1, duty);
    put(0, 50.0);
    demand(1, 1, duty);
    CHECK_EQ(duty[0], HOLD);
}

/* Both limbs at their strokes' tops (11), lowered (00): the fall lead (limb 1) first, past
 * halfway down, limb 0 above its hold top so that nothing is heated. */
static void lower_from_the_strokes(double *a, double *b)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint32_t k;
    setup();
    *a = 61.5;
    *b = 34.0;
    for (k = 0; k < SMOOTH_TICKS; k++) {
        put(0, *a);
        put(1, 50.5);
        demand(1, 1, duty);
    }
    CHECK(!ctl_coming_down()); /* held: nothing comes down */
    put(1, *b);
    demand(0, 0, duty);
    CHECK(!ctl_coming_down()); /* a new step: no drop seen yet */
}

/* ctl.h, CTL_FALL_PROGRESS_MS: the step's clock stands while every limb not settled at its
 * target comes down, not once they stop, nor for a wobble where they stopped, nor while a
 * coil is asked for more than the hold. */
static void test_a_fall_still_coming_down_stands_the_steps_clock_and_one_that_stopped_does_not(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint32_t k, paused = 0, quiet = (uint32_t)CTL_FALL_PROGRESS_MS * CFG_TICK_HZ / 1000u;
    double a, b;
    lower_from_the_strokes(&a, &b);
    for (k = 1; k <= 400u; k++) { /* 1° every 40 ticks (25°/s) each, coils off */
        if (k % 40u == 0u) {
            a -= 1.0;
            b -= 1.0;
        }
        put(0, a);
        put(1, b);
        demand(0, 0, duty);
        CHECK_EQ(duty[0], 0);
        CHECK_EQ(duty[1], 0);
        paused += ctl_coming_down();
    }
    CHECK(ctl_coming_down());
    CHECK(paused > 400u - 2u * SMOOTH_TICKS); /* from its first degree down */
    for (k = 0; k < 2u * quiet && ctl_coming_down(); k++) { /* they stop at 51.5° and 24° */
        put(0, a);
        put(1, b);
        demand(0, 0, duty);
    }
    CHECK(!ctl_coming_down());
    CHECK(k + 2u * CTL_REACH_EVERY >= quiet - SMOOTH_TICKS);
    CHECK(k <= quiet + SMOOTH_TICKS); /* the smoothed ψ comes down a little after them */
    for (k = 0, paused = 0; k < 10u * quiet; k++) { /* ±2° of wobble there, 10 Hz */
        double w = (k / 50u) % 2u ? 2.0 : -2.0;
        put(0, a + w);
        put(1, b + w);
        demand(0, 0, duty);
        paused += ctl_coming_down();
    }
    CHECK(paused <= 2u * quiet); /* one or two new lows, not one a swing */
    for (k = 1; k <= 200u; k++) { /* coming down again, limb 0 raised back to its stroke: heated */
        if (k % 40u == 0u) {
            b -= 1.0;
        }
        put(0, a);
        put(1, b);
        demand(1, 0, duty);
        CHECK_EQ(duty[0], DRIVE);
        CHECK(!ctl_coming_down());
    }
}

/* Step 11 from 00: the rise lead (limb 0) climbs 5 -> 17° at 100°/s (a coil transforming at a
 * nominal supply), then creeps at `creep` °/s below its band (19..21°) for `ms`: the rest of its
 * rise is the other coil's doing, not its own (R1 at full strokes with the left ψ* moved to 70°:
 * 3°/s, its coil 85 -> 166 °C at the drive duty). Its last duties and the other limb's. */
static void lead_rises_then_creeps(double fast_deg_s, double creep, uint32_t ms, uint16_t duty[CFG_N_ACTUATORS])
{
    uint32_t k;
    double psi = 5.0;
    setup();
    put(0, 5.0);
    put(1, 5.0);
    demand(1, 1, duty);
    CHECK_EQ(duty[0], DRIVE);
    while (psi < 17.0) {
        psi += fast_deg_s / (double)CFG_TICK_HZ;
        put(0, psi);
        put(1, 5.0);
        demand(1, 1, duty);
    }
    for (k = 0; k < ms * CFG_TICK_HZ / 1000u; k++) {
        put(0, psi + creep * (double)k / (double)CFG_TICK_HZ);
        put(1, 5.0);
        demand(1, 1, duty);
    }
}

static void test_a_rise_lead_whose_coil_is_spent_below_its_band_is_heated_no_more(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    /* 0.5 s of the creep: the knee watch has seen a window gaining less than 1/8 of its fastest */
    lead_rises_then_creeps(100.0, 3.0, 500u, duty);
    CHECK(ctl_stall(0) == CTL_STALL_NONE); /* not cut off: the others' climb may still lift it */
    CHECK_EQ(duty[0], HOLD);               /* its coil is through its transformation: warm, no more */
    CHECK_EQ(duty[1], DRIVE);              /* no longer the lead to wait for: the other climbs */
}

static void test_a_slow_rise_is_no_knee(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    /* 20°/s (a weak supply: 1.6° in a window, never 4°), then the same creep: as before the knee
     * watch, the lead heats on at the drive duty and the other waits */
    lead_rises_then_creeps(20.0, 3.0, 500u, duty);
    CHECK_EQ(duty[0], DRIVE);
    CHECK(duty[1] != DRIVE);
}

static void test_a_fast_rise_that_goes_on_is_no_knee(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    /* 100°/s, then 30°/s (2.4° a window, above 1/8 of 8°): still transforming */
    lead_rises_then_creeps(100.0, 30.0, 60u, duty);
    CHECK_EQ(duty[0], DRIVE);
}

int main(void)
{
    RUN(test_the_config_has_the_strokes);
    RUN(test_a_raised_limb_is_held_at_its_stroke_not_past_its_band);
    RUN(test_a_limb_settles_on_its_top_level_only_at_its_stroke);
    RUN(test_the_settle_edge_below_the_band_keeps_the_margin);
    RUN(test_moving_psi_star_past_the_stroke_gives_back_the_margin_hold);
    RUN(test_the_larger_stroke_crosses_first_and_the_others_wait_warm);
    RUN(test_a_limb_waiting_for_a_larger_stroke_is_kept_warm_only_for_a_while);
    RUN(test_a_limb_already_at_its_stroke_is_held_there_while_another_rises);
    RUN(test_limbs_climb_to_their_strokes_in_step);
    RUN(test_a_limb_still_climbing_to_its_stroke_is_not_hovering);
    RUN(test_a_limb_that_stops_climbing_short_of_its_stroke_settles_there);
    RUN(test_a_limb_relaxed_mid_climb_is_heated_on_while_it_still_climbs);
    RUN(test_a_climb_is_not_waited_for_longer_than_the_climb_limit);
    RUN(test_a_limb_waiting_for_another_in_step_is_not_hovering);
    RUN(test_a_limb_that_stops_just_past_its_band_is_held_at_the_hold_it_has_without_a_stroke);
    RUN(test_a_limb_that_reaches_its_top_level_late_is_held_where_it_stopped);
    RUN(test_climbing_in_step_waits_for_a_slow_limb_only_for_the_climb_limit);
    RUN(test_a_limb_that_stopped_short_caps_the_others_in_step);
    RUN(test_a_limb_stopped_short_in_an_earlier_step_caps_nothing);
    RUN(test_falling_together_the_others_are_held_at_their_strokes_until_the_fall_lead_is_down);
    RUN(test_climbing_in_step_waits_for_a_limb_only_while_it_still_rises);
    RUN(test_a_lagging_limb_given_up_is_not_waited_for_again_in_the_step);
    RUN(test_a_fall_still_coming_down_stands_the_steps_clock_and_one_that_stopped_does_not);
    RUN(test_a_rise_lead_whose_coil_is_spent_below_its_band_is_heated_no_more);
    RUN(test_a_slow_rise_is_no_knee);
    RUN(test_a_fast_rise_that_goes_on_is_no_knee);
    return UNIT_EXIT();
}
