/* Host unit tests of core/stall.c's hold watch (through ctl_demand) (CFG_HOLD_WATCH, ctl.h): a held limb that never
 * settled clear of its hold edge and stopped gaining is held where it stopped, and settled in its
 * level there if it rose into it and is past ψ*.
 * Config "r1-worn": two limbs, ψ* = 50°, band 49..51°, hold margin 2° (hold edge 53°, hold top
 * 54°), 1 kHz; on the simulated 80 mm body its own coil bends its end to 58°, 44° once worn (25 %
 * of its stroke lost), so the renderer builds the watch in (robot_body.worn_holds). */
#include "ctl_unit.h"
#include "unit.h"

#define HOVER_TICKS ((uint32_t)CTL_HOVER_MS * CFG_TICK_HZ / 1000u)
#define REACH_TICKS ((uint32_t)CTL_REACH_MS * CFG_TICK_HZ / 1000u)
/* Samples the smoothed ψ (1/16 of each new sample, psi.h) takes to follow a step of a few
 * degrees to within a tenth of one: 16 ln 30 ≈ 55. */
#define SMOOTH_TICKS 60u

/* Step 10 from a fresh controller: limb 0 rises from 40° at 25°/s to `stop`; with `heating`,
 * its coil is checked to heat at every tick of the way. */
static void ramp_to(double stop, int heating)
{
    uint16_t duty[CFG_N_ACTUATORS];
    double psi;
    setup();
    put(1, 0.0);
    for (psi = 40.0; psi < stop; psi += 0.025) {
        put(0, psi);
        demand(1, 0, duty);
        if (heating) {
            CHECK_EQ(duty[0], DRIVE);
        }
    }
}

/* Step 10: limb 0 rises from 40° at 25°/s to `stop` (level 1, short of its hold edge) and stays
 * there until the stall detector relaxes it (a hover time unsettled). Its coil heats all along. */
static void rise_to(double stop)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint32_t k;
    ramp_to(stop, 1);
    for (k = 0; k <= HOVER_TICKS + 1u && ctl_stall(0) == CTL_STALL_NONE; k++) {
        put(0, stop);
        demand(1, 0, duty);
        CHECK_EQ(duty[0], DRIVE); /* the bang-bang hold heats it towards its hold edge */
    }
    CHECK_EQ(ctl_stall(0), CTL_STALL_OSCILLATING);
    CHECK_EQ(psi_level(0), 1);
}

/* Three reach times at ψ = `deg`: limb 0 stays at level 1 and its coil heats at every tick. */
static void heated_at_level_1(double deg)
{
    uint16_t duty[CFG_N_ACTUATORS];
    int t;
    for (t = 0; t < 3 * (int)REACH_TICKS; t++) {
        put(0, deg);
        demand(1, 0, duty);
        CHECK_EQ(psi_level(0), 1);
        CHECK_EQ(duty[0], DRIVE);
    }
}

/* Ticks at ψ = `deg` until limb 0's coil is `on` (DRIVE) or off (0); -1: not within `ticks`,
 * -2: some other duty. */
static int ticks_until(double deg, int on, int ticks)
{
    uint16_t duty[CFG_N_ACTUATORS];
    int t;
    for (t = 0; t < ticks; t++) {
        put(0, deg);
        demand(1, 0, duty);
        if ((duty[0] != 0u && duty[0] != DRIVE) || duty[1] != 0u) {
            return -2; /* a duty the hold never asks for */
        }
        if ((duty[0] == DRIVE) == (on != 0)) {
            return t;
        }
    }
    return -1;
}

static void test_the_config_builds_the_hold_watch_in(void)
{
    CHECK_EQ(CFG_HOLD_WATCH, 1);
    CHECK_EQ(CFG_HOLD_MARGIN_CDEG, 200);
}

static void test_a_held_limb_that_stopped_short_of_its_hold_edge_is_held_where_it_stopped(void)
{
    int t;
    rise_to(52.8);
    /* clear of its band (51°), short of its hold edge (53°), no gain: off a reach time after its
     * last gain (the watch counts from its rise on, through the hover time rise_to has spent) */
    t = ticks_until(52.8, 0, 2 * (int)REACH_TICKS);
    CHECK(t >= 0);
    CHECK(t + (int)HOVER_TICKS >= (int)REACH_TICKS - 2 * (int)CTL_REACH_EVERY);
    CHECK(t + (int)HOVER_TICKS <= (int)REACH_TICKS + (int)SMOOTH_TICKS + 2 * (int)CTL_REACH_EVERY);
    /* held there: it stays off while its ψ stays where it stopped, or sags less than 1° */
    CHECK_EQ(ticks_until(52.8, 1, 3000), -1);
    CHECK_EQ(ticks_until(52.2, 1, 3000), -1);
    CHECK_EQ(ctl_stall(0), CTL_STALL_OSCILLATING);
}

static void test_a_limb_held_where_it_stopped_is_re_heated_once_it_sags_and_stopped_again(void)
{
    int t;
    rise_to(52.8);
    CHECK(ticks_until(52.8, 0, 2 * (int)REACH_TICKS) >= 0);
    /* 1.5° below where it stopped, still clear of its band: heated again once its smoothed ψ
     * got there (1° below the highest look that gained 0.4°: 1-1.4° below where it stopped) */
    t = ticks_until(51.3, 1, 1000);
    CHECK(t >= 0);
    CHECK(t <= (int)SMOOTH_TICKS + 2 * (int)CTL_REACH_EVERY);
    /* back where it stopped, no higher: off again a reach time after its last gain */
    t = ticks_until(52.8, 0, 3 * (int)REACH_TICKS);
    CHECK(t >= (int)REACH_TICKS - 2 * (int)CTL_REACH_EVERY);
    CHECK(t <= (int)REACH_TICKS + (int)SMOOTH_TICKS + 2 * (int)CTL_REACH_EVERY);
}

static void test_a_limb_that_drops_its_level_while_held_off_rises_back(void)
{
    /* a weak supply: sagged 1.5°, its re-heat gains nothing for a reach time and is cut; it
     * drops out of its level (below 49°) while its coil is off: the rise back is a new rise for
     * the reach watch, not one that stopped short (the watch's last look was not a gain) */
    uint16_t duty[CFG_N_ACTUATORS];
    int t;
    rise_to(52.8);
    CHECK(ticks_until(52.8, 0, 2 * (int)REACH_TICKS) >= 0);
    CHECK(ticks_until(51.3, 1, 1000) >= 0);
    CHECK(ticks_until(51.3, 0, 2 * (int)REACH_TICKS) >= 0); /* the re-heat, cut */
    for (t = 0; t < 1000; t++) {
        put(0, 45.0);
        demand(1, 0, duty);
        CHECK_EQ(psi_level(0), 0);
        CHECK_EQ(duty[0], DRIVE); /* heated back up, at once and for as long as a rise may take */
    }
    CHECK(ctl_stall(0) != CTL_STALL_UNREACHABLE);
}

static void test_a_limb_that_stopped_inside_its_band_past_psi_star_settles_there(void)
{
    /* at its level (entered at 51.2°), back inside its band (50.5°, past ψ* = 50°) and gaining
     * nothing: its coil has given all it has, and it settles in its level where it is, its coil
     * off (heated on, the one-actuator R1's worn far end reached 151 °C and the step its
     * timeout); it stays settled while past ψ*, and back below ψ* (its pad switched back) it
     * is not, though the classifier keeps its level down to the band's lower edge (49°) */
    uint16_t duty[CFG_N_ACTUATORS];
    int t;
    rise_to(51.2);
    CHECK(ticks_until(50.5, 0, 2 * (int)REACH_TICKS) >= 0);
    for (t = 0; t < 100 && !psi_settled(0); t++) {
        put(0, 50.5);
        demand(1, 0, duty);
    }
    CHECK(psi_settled(0));
    CHECK_EQ(psi_level(0), 1);
    CHECK_EQ(duty[0], 0);
    for (t = 0; t < 100; t++) {
        put(0, 50.2);
        demand(1, 0, duty);
    }
    CHECK(psi_settled(0));
    CHECK_EQ(psi_level(0), 1);
    for (t = 0; t < 100; t++) {
        put(0, 49.7);
        demand(1, 0, duty);
    }
    CHECK(!psi_settled(0));
    CHECK_EQ(psi_level(0), 1);
    for (t = 0; t < 100; t++) {
        put(0, 48.8);
        demand(1, 0, duty);
    }
    CHECK_EQ(psi_level(0), 0); /* out of its level, as the classifier says */
}

static void test_a_limb_that_stopped_inside_its_band_short_of_psi_star_is_held_off_unsettled(void)
{
    /* back inside its band short of ψ* (49.6°): its pad has not switched, so the step is not
     * reached, but its coil, which gains nothing, is off all the same (the step's timeout
     * reports it, the coil cooling) */
    uint16_t duty[CFG_N_ACTUATORS];
    int t;
    rise_to(51.2);
    CHECK(ticks_until(49.6, 0, 2 * (int)REACH_TICKS) >= 0);
    for (t = 0; t < 300; t++) {
        put(0, 49.6);
        demand(1, 0, duty);
        CHECK_EQ(duty[0], 0);
        CHECK(!psi_settled(0));
    }
    CHECK_EQ(psi_level(0), 1);
}

static void test_a_held_limb_that_sags_into_its_band_is_heated(void)
{
    /* settled at its hold (53.5°), then sagged into its band (50.5°): no rise in this step
     * brought it there, and its coil may be in its dead time: heated, not held where it is */
    uint16_t duty[CFG_N_ACTUATORS];
    setup();
    put(1, 0.0);
    put(0, 53.5);
    demand(1, 0, duty);
    CHECK(psi_settled(0));
    heated_at_level_1(50.5);
}

static void test_a_limb_that_rose_and_settled_at_its_hold_then_sagged_into_its_band_is_heated(void)
{
    /* it rose alone to its hold top (54.5°) and settled there by the margins; later it sags into
     * its band (50.5°): a re-heat, its coil perhaps in its dead time, not a rise that stopped
     * short, so it is heated, not cut and settled there (the rise of its step is long past) */
    uint16_t duty[CFG_N_ACTUATORS];
    int t;
    ramp_to(54.5, 0);
    for (t = 0; t < 200; t++) {
        put(0, 54.5);
        demand(1, 0, duty);
    }
    CHECK(psi_settled(0));
    CHECK_EQ(ctl_stall(0), CTL_STALL_NONE);
    heated_at_level_1(50.5);
}

static void test_a_limb_held_where_it_stopped_that_sags_is_re_heated_and_cut_again_from_there(void)
{
    /* held where it stopped (52.8°), it sags 1.5° and its coil cannot lift it back: the re-heat
     * is watched from where it sagged to, so it is cut a reach time later and stays off until it
     * sags a further degree (kept at its old highest, it was heated 20 looks in 21) */
    uint16_t duty[CFG_N_ACTUATORS];
    int t, on = 0;
    rise_to(52.8);
    CHECK(ticks_until(52.8, 0, 2 * (int)REACH_TICKS) >= 0);
    for (t = 0; t < 3000; t++) {
        put(0, 51.3);
        demand(1, 0, duty);
        on += duty[0] == DRIVE;
    }
    CHECK(on >= (int)REACH_TICKS - 2 * (int)CTL_REACH_EVERY);
    CHECK(on <= (int)REACH_TICKS + (int)SMOOTH_TICKS + 2 * (int)CTL_REACH_EVERY);
}

static void test_a_held_limb_still_gaining_keeps_heating_to_its_hold_top(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    int t;
    ramp_to(52.0, 0); /* risen into its level, short of its hold edge */
    for (t = 0; t < 950; t++) { /* creeping on at 2 °/s (0.64° per reach time), to 53.9° */
        put(0, 52.0 + 0.002 * t);
        demand(1, 0, duty);
        CHECK_EQ(duty[0], DRIVE);
    }
    put(0, 54.2); /* at its hold top: off, as any bang-bang hold */
    demand(1, 0, duty);
    CHECK_EQ(duty[0], 0);
}

static void test_a_limb_that_settled_is_not_watched(void)
{
    /* held normally (settled between its hold edge and top): the bang-bang hold as always, its
     * coil heated below the hold edge for as long as it takes */
    uint16_t duty[CFG_N_ACTUATORS];
    int t;
    setup();
    put(1, 0.0);
    put(0, 53.5);
    demand(1, 0, duty);
    CHECK_EQ(ctl_stall(0), CTL_STALL_NONE);
    CHECK(psi_settled(0));
    for (t = 0; t < 2 * (int)REACH_TICKS; t++) {
        put(0, 52.8); /* sagged below the hold edge, no gain for two reach times */
        demand(1, 0, duty);
        CHECK_EQ(duty[0], DRIVE);
    }
    CHECK_EQ(ctl_stall(0), CTL_STALL_NONE);
}

/* The coil-wide knee (ctl.c KNEE_COIL, ctl.h CTL_KNEE_MS), built with the hold watch: a coil asked
 * for the drive duty whose own end moved fast in this heat and then stopped is through its
 * transformation, and is kept at no more than the hold duty for the rest of the step. Its
 * verdict comes a window or two after the stop (80 ms each, the smoothed ψ's lag on top). */
#define KNEE_TICKS ((int)((uint32_t)CTL_KNEE_MS * CFG_TICK_HZ / 1000u))
#define KNEE_BY (2 * KNEE_TICKS + (int)SMOOTH_TICKS + 2 * (int)CTL_REACH_EVERY)

/* Ticks of `ticks` at limb 0 = `deg0`, limb 1 creeping from `from1` at 1.5°/s (0.48° per reach
 * time: the hold watch never sees it stop), targets (1, 1), until coil 0 leaves the drive
 * duty (-1: never); after that it must stay at no more than the hold duty. */
static int creep_until_cut(double deg0, int limb, double from, int ticks)
{
    uint16_t duty[CFG_N_ACTUATORS];
    int t, cut = -1;
    for (t = 0; t < ticks; t++) {
        put(limb, from + 0.0015 * t);
        if (limb != 0) {
            put(0, deg0);
        }
        demand(1, (uint8_t)(limb != 0), duty);
        if (cut < 0 && duty[0] != DRIVE) {
            cut = t;
        }
        if (cut >= 0 && duty[0] > HOLD) {
            return -2; /* heated past the hold duty again in the same step */
        }
    }
    return cut;
}

static void test_a_coil_whose_end_stopped_after_a_fast_rise_is_held_at_the_hold_duty(void)
{
    /* limb 0 rises at 100°/s (a transforming coil: 8° in a window) into its level, then its
     * end creeps on by tenths, 1.5°/s, below its hold edge. Before the coil-wide knee the hold
     * watch never saw it stop and the coil was heated at the drive duty for as long as the creep
     * lasted (the one-actuator R1 worn by 14,758 cycles: 136 °C); now it is cut to the hold duty
     * a window or two after its end stopped moving fast. */
    uint16_t duty[CFG_N_ACTUATORS];
    double psi;
    int t;
    setup();
    put(1, 0.0);
    for (psi = 40.0; psi < 51.5; psi += 0.1) {
        put(0, psi);
        demand(1, 0, duty);
        CHECK_EQ(duty[0], DRIVE);
    }
    t = creep_until_cut(0.0, 0, 51.5, 1000);
    CHECK(t >= 0);
    CHECK(t <= KNEE_BY);
    /* the robot's next step starts every coil over: a rise from below heats at the drive duty */
    for (t = 0; t < 200; t++) {
        put(0, 45.0);
        demand(0, 0, duty);
    }
    for (t = 0; t < 100; t++) {
        put(0, 40.0);
        demand(1, 0, duty);
        CHECK_EQ(duty[0], DRIVE);
    }
}

static void test_a_shared_coil_is_judged_by_the_end_it_bends_not_the_limb_it_heats_for(void)
{
    /* The one-actuator R1's step 10 -> 11: both limbs on coil 0 (a run-time map), limb 0 held
     * high, limb 1 rising. The coil bends limb 0's end fast (15° in 150 ms) and lifts limb 1
     * only through the body; limb 0's end stops, limb 1 creeps into its level by tenths. The
     * coil is heated for limb 1, whose own watch never armed; limb 0's end tells that it is
     * through its transformation: the hold duty from then on. */
    const uint8_t both_on_0[2] = {0, 0};
    uint16_t duty[CFG_N_ACTUATORS];
    uint16_t bad = 0;
    int k, t;
    setup();
    CHECK_EQ(limbmap_set(both_on_0, 2, &bad), 0);
    for (k = 0; k <= 150; k++) {
        put(0, 56.0 + 0.1 * k);   /* its own end: 100°/s */
        put(1, 40.0 + 0.075 * k); /* through the body: 75°/s, into its level at 51° */
        demand(1, 1, duty);
        CHECK_EQ(duty[0], DRIVE);
    }
    t = creep_until_cut(71.0, 1, 51.25, 1000);
    CHECK(t >= 0);
    CHECK(t <= KNEE_BY);
}

static void test_a_fast_rise_that_goes_on_to_its_hold_top_is_no_knee(void)
{
    /* 100°/s all the way from 40° to past its hold top (54°): heated at the drive duty at every
     * tick of the way, then off as the bang-bang hold says */
    uint16_t duty[CFG_N_ACTUATORS];
    double psi;
    setup();
    put(1, 0.0);
    for (psi = 40.0; psi < 54.0; psi += 0.1) {
        put(0, psi);
        demand(1, 0, duty);
        CHECK_EQ(duty[0], DRIVE);
    }
    put(0, 54.3);
    demand(1, 0, duty);
    CHECK_EQ(duty[0], 0);
}

static void test_a_step_of_the_reading_as_a_heat_starts_is_no_knee(void)
{
    /* START levels the robot on the ground it rested on: the reading of a limb at rest on a
     * decline steps by the slope (here 8°) as its first rise from cold begins, and the smoothed ψ glides after
     * it within the first window of the heat. That window is not the coil's (from below As it
     * gains nothing for its dead time, here 250 ms), and counted as fast, the dead time after it
     * read as the knee: the coil was held at the hold duty for 5 s (the one-actuator R1 on the
     * claim bench's decline, 2.31 -> 2.00 mm/s). Heated at the drive duty through the dead time
     * and the rise, to its hold top. */
    uint16_t duty[CFG_N_ACTUATORS];
    double psi;
    int t;
    setup();
    put(1, 0.0);
    for (t = 0; t < 195; t++) { /* the knee's look (ctl_look 4 of 16) falls on the heat's first tick */
        put(0, -8.0);
        demand(0, 0, duty);
    }
    for (t = 0; t < 250; t++) {
        put(0, 0.0);
        demand(1, 0, duty);
        CHECK_EQ(duty[0], DRIVE);
    }
    for (psi = 0.0; psi < 54.0; psi += 0.1) {
        put(0, psi);
        demand(1, 0, duty);
        CHECK_EQ(duty[0], DRIVE);
    }
}

int main(void)
{
    RUN(test_the_config_builds_the_hold_watch_in);
    RUN(test_a_held_limb_that_stopped_short_of_its_hold_edge_is_held_where_it_stopped);
    RUN(test_a_limb_held_where_it_stopped_is_re_heated_once_it_sags_and_stopped_again);
    RUN(test_a_limb_that_drops_its_level_while_held_off_rises_back);
    RUN(test_a_limb_that_stopped_inside_its_band_past_psi_star_settles_there);
    RUN(test_a_limb_that_stopped_inside_its_band_short_of_psi_star_is_held_off_unsettled);
    RUN(test_a_held_limb_that_sags_into_its_band_is_heated);
    RUN(test_a_limb_that_rose_and_settled_at_its_hold_then_sagged_into_its_band_is_heated);
    RUN(test_a_limb_held_where_it_stopped_that_sags_is_re_heated_and_cut_again_from_there);
    RUN(test_a_held_limb_still_gaining_keeps_heating_to_its_hold_top);
    RUN(test_a_limb_that_settled_is_not_watched);
    RUN(test_a_coil_whose_end_stopped_after_a_fast_rise_is_held_at_the_hold_duty);
    RUN(test_a_shared_coil_is_judged_by_the_end_it_bends_not_the_limb_it_heats_for);
    RUN(test_a_fast_rise_that_goes_on_to_its_hold_top_is_no_knee);
    RUN(test_a_step_of_the_reading_as_a_heat_starts_is_no_knee);
    return UNIT_EXIT();
}
