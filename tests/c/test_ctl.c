/* Host unit tests of core/ctl.c: measured level vs target → duty per actuator.
 * Config: two limbs, ψ* = 20°, band 19..21°, hold margin 1° (a held level is kept between
 * the hold edge 22° and the hold top 23°, the settle edge below the band is 18°), limb i
 * driven by actuator i. Built twice: against r1-fast (no boost) and r1-boost
 * (control.boost_ms = 200, CTL_BOOST_MS). */
#include "ctl_unit.h"
#include "unit.h"

/* Heating a rise: the drive duty, or with a boost (control.boost_ms, the r1-boost config) the
 * duty ceiling once the rise lagged. */
#define HEATING(d) ((d) == DRIVE || (CTL_BOOST_MS && (d) == CFG_MAX_DUTY_PM))

static void test_limb_that_must_go_up_gets_the_drive_duty(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    put(0, 0.0);
    put(1, 0.0);
    demand(1, 0, duty);
    CHECK_EQ(duty[0], DRIVE);
    CHECK_EQ(duty[1], 0);
}

static void test_limb_that_must_go_down_is_switched_off(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    put(0, 30.0);
    put(1, 30.0);
    demand(0, 0, duty);
    CHECK_EQ(duty[0], 0);
    CHECK_EQ(duty[1], 0);
}

static void test_holding_a_raised_level_is_bang_bang_with_hysteresis_on_psi(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    CHECK_EQ(CFG_HOLD_MARGIN_CDEG, 100);
    CHECK_EQ(PSI_HOLD_BAND_CDEG, 100); /* hold edge 22°, hold top 23° */
    put(0, 30.0);
    demand(1, 0, duty);
    CHECK_EQ(duty[0], 0); /* above the hold top: off, no fixed hold duty */
    put(0, 22.5);         /* between edge and top, coming down: stays off */
    demand(1, 0, duty);
    CHECK_EQ(duty[0], 0);
    put(0, 20.0); /* inside the band: still level 1, sagging: drive */
    CHECK_EQ(psi_level(0), 1);
    demand(1, 0, duty);
    CHECK_EQ(duty[0], DRIVE);
    put(0, 22.5); /* above the hold edge but below the top, going up: keeps heating */
    demand(1, 0, duty);
    CHECK_EQ(duty[0], DRIVE);
    put(0, 23.2); /* reached the top: off */
    demand(1, 0, duty);
    CHECK_EQ(duty[0], 0);
    put(0, 22.2); /* coming down again, above the edge: off */
    demand(1, 0, duty);
    CHECK_EQ(duty[0], 0);
    put(0, 21.8); /* below the edge: heat */
    demand(1, 0, duty);
    CHECK_EQ(duty[0], DRIVE);
}

static void test_the_hold_duty_is_not_used_to_hold(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint8_t target[CFG_N_LIMBS] = {1, 0};
    setup();
    put(0, 30.0);
    ctl_demand(target, DRIVE, HOLD, duty);
    CHECK_EQ(duty[0], 0);
    put(0, 20.0);
    ctl_demand(target, DRIVE, 0, duty);
    CHECK_EQ(duty[0], DRIVE);
}

static void test_limbs_rising_together_wait_for_the_farthest(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    put(0, 15.5); /* 5.5° to go to the band's upper edge (the 6° progress edge) */
    put(1, 5.0);  /* 16° to go (the 20° progress edge) */
    demand(1, 1, duty);
    CHECK_EQ(duty[0], HOLD);
    CHECK_EQ(duty[1], DRIVE);
    put(1, 12.0); /* 9° to go (the 10° edge): still more than 2° behind */
    demand(1, 1, duty);
    CHECK_EQ(duty[0], HOLD);
    put(1, 13.5); /* 7.5° to go (the 8° edge): within 2°, both heat */
    demand(1, 1, duty);
    CHECK_EQ(duty[0], DRIVE);
    CHECK_EQ(duty[1], DRIVE);
}

static void test_a_limb_rising_while_another_falls_waits_near_its_crossing(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    put(0, 5.0);  /* rising, 16° to go */
    put(1, 30.0); /* level 1, falling, 11° above the band's lower edge */
    demand(1, 0, duty);
    CHECK_EQ(duty[0], DRIVE); /* far from its crossing: climbs */
    CHECK_EQ(duty[1], 0);     /* a falling limb is never held back */
    put(0, 16.0);             /* 5° to go: inside the 6° zone, waits */
    demand(1, 0, duty);
    CHECK_EQ(duty[0], HOLD);
    CHECK_EQ(duty[1], 0);
    put(1, 20.5); /* the falling limb is 1.5° from crossing: go */
    demand(1, 0, duty);
    CHECK_EQ(duty[0], DRIVE);
    CHECK_EQ(duty[1], 0);
}

static void test_a_falling_limb_waits_warm_while_a_held_limb_sags_but_not_for_long(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint32_t k, n = (uint32_t)CTL_SAG_WAIT_MS * CFG_TICK_HZ / 1000u;
    setup();
    put(0, 30.0);
    put(1, 30.0);
    demand(1, 0, duty); /* limb 0 holds (above its top: off), limb 1 falls */
    CHECK_EQ(duty[0], 0);
    CHECK_EQ(duty[1], 0);
    put(0, 20.5); /* limb 0 sags below its hold edge (still level 1) */
    CHECK_EQ(psi_level(0), 1);
    for (k = 0; k < n; k++) {
        demand(1, 0, duty);
        CHECK_EQ(duty[0], DRIVE); /* the sagging limb re-heats its own coil */
        CHECK_EQ(duty[1], HOLD);  /* the falling one is kept warm: it stops relaxing */
    }
    demand(1, 0, duty); /* CTL_SAG_WAIT_MS used up: released for the rest of the step (with
                         * several limbs held, one of them nearly always sags, and a falling
                         * coil kept warm for good would never cross) */
    CHECK_EQ(duty[0], DRIVE);
    CHECK_EQ(duty[1], 0);
    put(0, 23.0); /* caught */
    demand(1, 0, duty);
    CHECK_EQ(duty[1], 0);
}

static void test_holding_level_zero_never_heats(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    put(0, 5.0);
    put(1, 20.5);
    demand(0, 0, duty);
    CHECK_EQ(duty[0], 0);
    CHECK_EQ(duty[1], 0);
}

static void test_unknown_level_never_heats(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    demand(1, 1, duty);
    CHECK_EQ(duty[0], 0);
    CHECK_EQ(duty[1], 0);
}

static void test_a_limb_crossing_back_and_forth_is_oscillating_and_settles_on_the_band(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    put(0, 10.0);
    put(1, 0.0);
    demand(1, 0, duty);
    CHECK_EQ(ctl_stall(0), CTL_STALL_NONE);
    put(0, 21.5); /* up: level 1, inside the margin (not settled) */
    demand(1, 0, duty);
    put(0, 18.5); /* back down below the band */
    demand(1, 0, duty);
    CHECK_EQ(ctl_stall(0), CTL_STALL_NONE); /* two crossings: 0->1->0 */
    put(0, 21.5);
    demand(1, 0, duty);
    CHECK_EQ(ctl_stall(0), CTL_STALL_OSCILLATING);
    CHECK_EQ(psi_settled(0), 0); /* margins still required until the next sample */
    put(0, 21.5);
    CHECK_EQ(psi_settled(0), 1); /* relaxed: above the band's upper edge is enough */
    demand(0, 0, duty);          /* a new step clears it */
    CHECK_EQ(ctl_stall(0), CTL_STALL_NONE);
}

static void test_a_limb_hovering_unsettled_at_its_level_is_oscillating(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint32_t k;
    setup();
    put(0, 21.5); /* level 1 but inside the hold margin */
    put(1, 0.0);
    for (k = 0; k <= (uint32_t)CTL_HOVER_MS * CFG_TICK_HZ / 1000u; k++) {
        demand(1, 0, duty);
        CHECK_EQ(duty[0], DRIVE); /* the hold keeps heating it towards the top */
    }
    CHECK_EQ(ctl_stall(0), CTL_STALL_OSCILLATING);
}

static void test_a_limb_that_heats_without_progress_is_unreachable_and_cut_off(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint32_t k, n = (uint32_t)CTL_STALL_MS * CFG_TICK_HZ / 1000u;
    setup();
    put(0, 5.0);
    put(1, 0.0);
    for (k = 0; k < n / 2u; k++) {
        demand(1, 0, duty);
    }
    put(0, 7.0); /* one progress edge closer (14° to go): the clock restarts; a rise of 2°, not
                  * the 3° the reach watch needs (below), so this is the slow stall */
    for (k = 0; k < n; k++) {
        demand(1, 0, duty);
        CHECK(duty[0] == DRIVE || duty[0] == CFG_MAX_DUTY_PM); /* boosted once it lags */
    }
    CHECK_EQ(ctl_stall(0), CTL_STALL_NONE);
    demand(1, 0, duty);
    CHECK_EQ(ctl_stall(0), CTL_STALL_UNREACHABLE);
    CHECK_EQ(duty[0], 0); /* cold coil when the state timeout comes */
    CHECK_EQ(duty[1], 0);
    demand(0, 0, duty); /* another step: forgotten */
    CHECK_EQ(ctl_stall(0), CTL_STALL_NONE);
}

#if CTL_BOOST_MS
static void test_a_limb_whose_rise_lags_is_boosted_to_the_duty_ceiling_until_the_next_start(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint32_t k, n = (uint32_t)CTL_BOOST_MS * CFG_TICK_HZ / 1000u;
    setup();
    put(0, 5.0);
    put(1, 0.0);
    for (k = 0; k <= n; k++) { /* the first call sets the reference: n + 1 calls */
        demand(1, 0, duty);
        CHECK_EQ(duty[0], DRIVE); /* the robot file's drive duty while it may still be warming up */
    }
    demand(1, 0, duty);
    CHECK_EQ(duty[0], CFG_MAX_DUTY_PM); /* no progress edge for CTL_BOOST_MS: the build's ceiling */
    CHECK_EQ(duty[1], 0);
    put(0, 10.0); /* progress: the limb keeps the ceiling (its coil lags: it will again) */
    demand(1, 0, duty);
    CHECK_EQ(duty[0], CFG_MAX_DUTY_PM);
    put(0, 30.0); /* held: a sag below the hold edge re-heats at the ceiling too */
    demand(1, 0, duty);
    put(0, 21.5);
    demand(1, 0, duty);
    CHECK_EQ(duty[0], CFG_MAX_DUTY_PM);
    ctl_reset(); /* a new START: the drive duty again */
    put(0, 5.0);
    demand(1, 0, duty);
    CHECK_EQ(duty[0], DRIVE);
}

#endif

/* Limb 0 rises from 8° at 25°/s to `stop` (short of its band at 21°) and stays there, limb 1
 * down at 0° or, `other_falls`, falling from 30°; returns the ticks from the stop to limb 0's
 * coil's cut (-1: none within `ticks`, -2: not heated on its way up). */
static int ticks_to_cut_after_stopping_at(double stop, int ticks, int other_falls)
{
    uint16_t duty[CFG_N_ACTUATORS];
    double psi;
    int t;
    setup();
    put(1, other_falls ? 30.0 : 0.0);
    if (other_falls) {
        put(1, 20.5); /* level 1 still, about to cross down: limb 0 need not wait for it */
    }
    for (psi = 8.0; psi < stop; psi += 0.025) {
        put(0, psi);
        demand(1, 0, duty);
        if (duty[0] != DRIVE) {
            return -2;
        }
    }
    for (t = 0; t < ticks; t++) {
        put(0, stop);
        demand(1, 0, duty);
        if (duty[0] == 0u) {
            return t;
        }
    }
    return -1;
}

static void test_a_rise_that_stops_short_of_its_level_is_cut_off_at_its_reach(void)
{
    /* rose 3° or more from its lowest, then nothing for CTL_REACH_MS: cannot reach */
    int t = ticks_to_cut_after_stopping_at(16.0, 2000, 0);
    CHECK(t >= (int)CTL_REACH_MS - 2 * (int)CTL_REACH_EVERY); /* its last gain came a look or two before */
    CHECK(t <= (int)CTL_REACH_MS + 2 * (int)CTL_REACH_EVERY);
    CHECK_EQ(ctl_stall(0), CTL_STALL_UNREACHABLE);
    /* a rise of 2° that stops is the slow stall's (CTL_STALL_MS), not the reach watch's */
    CHECK_EQ(ticks_to_cut_after_stopping_at(10.0, 2000, 0), -1);
}

static void test_a_rise_that_still_creeps_or_has_not_begun_keeps_heating(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    double psi;
    int t;
    setup();
    put(1, 0.0);
    for (psi = 8.0; psi < 14.0; psi += 0.025) { /* 25 °/s */
        put(0, psi);
        demand(1, 0, duty);
    }
    for (t = 0; t < 2000; t++) { /* then creeping at 2 °/s (a coil at a weak supply's equilibrium) */
        put(0, 14.0 + 0.002 * t);
        demand(1, 0, duty);
        CHECK(HEATING(duty[0]));
    }
    setup();
    put(1, 0.0);
    for (t = 0; t < 2000; t++) { /* flat, a cool coil heating back to As, with 1.5° of IMU noise */
        put(0, 8.0 + ((t / 16) % 2 ? 1.5 : 0.0));
        demand(1, 0, duty);
        CHECK(HEATING(duty[0]));
    }
}

/* A deterministic Gaussian-ish noise of about `sd` degrees (sum of four uniforms). */
static double noise(double sd)
{
    static uint32_t x = 12345u;
    double sum = 0.0;
    int k;
    for (k = 0; k < 4; k++) {
        x = x * 1664525u + 1013904223u;
        sum += (double)(x >> 8) / 16777216.0 - 0.5;
    }
    return sum * sd * 1.732;
}

static void test_a_creeping_rise_under_imu_noise_keeps_heating(void)
{
    /* 1.5° of noise on every sample (the claim bench's strong imu_noise_deg): on raw samples the
     * looks spread over 7°, a 'rise' of 3° and then a highest look not beaten for 400 ms */
    uint16_t duty[CFG_N_ACTUATORS];
    double psi;
    int t;
    setup();
    put(1, 0.0);
    for (psi = 8.0; psi < 11.0; psi += 0.025) {
        put(0, psi + noise(1.5));
        demand(1, 0, duty);
    }
    for (t = 0; t < 1000; t++) { /* creeping at 3 °/s, to 14° (noise keeps it below its band) */
        put(0, 11.0 + 0.003 * t + noise(1.5));
        demand(1, 0, duty);
        CHECK(HEATING(duty[0]));
    }
}

static void test_no_reach_while_another_limb_moves(void)
{
    /* limb 1 falls in the same step: the body couples them, and limb 0's ψ may stall for that */
    CHECK_EQ(ticks_to_cut_after_stopping_at(16.0, 1000, 1), -1);
    CHECK_EQ(ctl_stall(0), CTL_STALL_NONE);
}

int main(void)
{
    RUN(test_a_rise_that_stops_short_of_its_level_is_cut_off_at_its_reach);
    RUN(test_a_rise_that_still_creeps_or_has_not_begun_keeps_heating);
    RUN(test_a_creeping_rise_under_imu_noise_keeps_heating);
    RUN(test_no_reach_while_another_limb_moves);
    RUN(test_limb_that_must_go_up_gets_the_drive_duty);
    RUN(test_limb_that_must_go_down_is_switched_off);
    RUN(test_holding_a_raised_level_is_bang_bang_with_hysteresis_on_psi);
    RUN(test_the_hold_duty_is_not_used_to_hold);
    RUN(test_a_limb_crossing_back_and_forth_is_oscillating_and_settles_on_the_band);
    RUN(test_a_limb_hovering_unsettled_at_its_level_is_oscillating);
    RUN(test_a_limb_that_heats_without_progress_is_unreachable_and_cut_off);
#if CTL_BOOST_MS
    RUN(test_a_limb_whose_rise_lags_is_boosted_to_the_duty_ceiling_until_the_next_start);
#endif
    RUN(test_limbs_rising_together_wait_for_the_farthest);
    RUN(test_a_limb_rising_while_another_falls_waits_near_its_crossing);
    RUN(test_a_falling_limb_waits_warm_while_a_held_limb_sags_but_not_for_long);
    RUN(test_holding_level_zero_never_heats);
    RUN(test_unknown_level_never_heats);
    return UNIT_EXIT();
}
