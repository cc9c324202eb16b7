/* Host unit tests of core/seq.c, the gait sequencer. Config: paper R1 (every off-diagonal
 * transition allowed), hold 10 ms = 10 ticks, state timeout 200 ms = 200 ticks; gait
 * table +x: #0 = 00 10 11 01, #1 = 00 10; -x: none. */
#include "psi.h"
#include "imucheck.h"
#include "seq.h"
#include "unit.h"

static void setup(void)
{
    psi_init();
    seq_init();
}

static uint8_t ticks(uint32_t n, cfg_state_t measured)
{
    uint8_t ev = 0;
    while (n--) {
        ev = (uint8_t)(ev | seq_tick(measured));
    }
    return ev;
}

static void test_gait_table_holds_the_rendered_gaits(void)
{
    setup();
    CHECK_EQ(seq_gait_count(SEQ_DIR_PX), 2);
    CHECK_EQ(seq_gait_count(SEQ_DIR_MX), 0);
    CHECK_EQ(seq_start(SEQ_DIR_PX, 0, IMUCHECK_UNKNOWN), SEQ_OK);
    CHECK_EQ(seq_target(), 0);
}

static void test_advances_to_the_next_step_after_target_held_for_hold_ticks(void)
{
    setup();
    CHECK_EQ(seq_start(SEQ_DIR_PX, 0, 0), SEQ_OK);
    CHECK_EQ(seq_target(), 0);
    CHECK(!(ticks(CFG_HOLD_TICKS - 1u, 0) & SEQ_EV_ADVANCED));
    CHECK(seq_holding());
    CHECK(seq_tick(0) & SEQ_EV_ADVANCED);
    CHECK_EQ(seq_target(), 2);
    CHECK_EQ(seq_step(), 1);
}

static void test_hold_restarts_when_the_state_leaves_the_target(void)
{
    setup();
    seq_start(SEQ_DIR_PX, 0, 0);
    ticks(CFG_HOLD_TICKS - 2u, 0);
    seq_tick(1); /* a flicker */
    CHECK(!(ticks(CFG_HOLD_TICKS - 1u, 0) & SEQ_EV_ADVANCED));
    CHECK(seq_tick(0) & SEQ_EV_ADVANCED);
}

static void test_reached_is_reported_once_per_step(void)
{
    setup();
    seq_start(SEQ_DIR_PX, 0, 0);
    CHECK(seq_tick(0) & SEQ_EV_REACHED);
    CHECK(!(seq_tick(0) & SEQ_EV_REACHED));
    seq_tick(3);
    CHECK(!(seq_tick(0) & SEQ_EV_REACHED));
}

/* TELEMETRY's HOLDING flag (telemetry.c): set while the step's target is measured, not from
 * its first reach to the end of the step (a limb that fell back is not holding). */
static void test_holding_is_only_while_the_target_is_measured(void)
{
    setup();
    seq_start(SEQ_DIR_PX, 0, 0);
    seq_tick(2); /* away before it is reached */
    CHECK(!seq_holding());
    CHECK(seq_tick(0) & SEQ_EV_REACHED);
    CHECK(seq_holding());
    CHECK(seq_tick(1) & SEQ_EV_AWAY); /* lost: a limb fell back */
    CHECK(!seq_holding());
    CHECK(!(seq_tick(0) & SEQ_EV_REACHED)); /* re-reached: REACHED stays once per step */
    CHECK(seq_holding());
    CHECK(ticks(CFG_HOLD_TICKS - 1u, 0) & SEQ_EV_ADVANCED);
    CHECK_EQ(seq_target(), 2);
    CHECK(!seq_holding()); /* the next step's target is not reached yet */
    seq_tick(2);
    CHECK(seq_holding());
    seq_stop();
    CHECK(!seq_holding());
}

static void test_step_not_completed_within_timeout_stops_with_a_timeout_event(void)
{
    setup();
    seq_start(SEQ_DIR_PX, 0, 0);
    ticks(CFG_HOLD_TICKS, 0); /* now waiting for state 2 (10) */
    CHECK_EQ(seq_target(), 2);
    CHECK(!(ticks(CFG_STATE_TIMEOUT_TICKS - 1u, 0) & SEQ_EV_TIMEOUT));
    CHECK(seq_running());
    CHECK(seq_tick(0) & SEQ_EV_TIMEOUT);
    CHECK(!seq_running());
    CHECK_EQ(seq_tick(2), 0); /* stopped: nothing more happens */
}

static void test_a_target_held_longer_than_the_timeout_advances_without_a_timeout(void)
{
    uint8_t ev;
    setup();
    seq_set_hold(CFG_STATE_TIMEOUT_TICKS + 50u); /* SET_PARAM hold_ms above state_timeout_ms */
    seq_start(SEQ_DIR_PX, 0, 0);
    ev = ticks(CFG_STATE_TIMEOUT_TICKS + 49u, 0);
    CHECK(!(ev & (SEQ_EV_TIMEOUT | SEQ_EV_ADVANCED)));
    CHECK(seq_running());
    CHECK(seq_tick(0) & SEQ_EV_ADVANCED);
    CHECK_EQ(seq_target(), 2);
    /* a target lost after a long hold has the step's time away from it left, no more */
    ticks(CFG_STATE_TIMEOUT_TICKS + 10u, 2); /* reached at once, held */
    CHECK(seq_running());
    CHECK(!(ticks(CFG_STATE_TIMEOUT_TICKS - 1u, 0) & SEQ_EV_TIMEOUT));
    CHECK(seq_tick(0) & SEQ_EV_TIMEOUT);
}

static void test_time_away_from_the_target_adds_up_over_a_flickering_step(void)
{
    uint32_t away = 0;
    setup();
    seq_start(SEQ_DIR_PX, 0, 0);
    ticks(CFG_HOLD_TICKS, 0); /* now waiting for 10 */
    while (away + 10u < CFG_STATE_TIMEOUT_TICKS) { /* 10 ticks away, 1 at the target, ... */
        CHECK(!(ticks(10, 0) & SEQ_EV_TIMEOUT));
        CHECK(!(seq_tick(2) & SEQ_EV_ADVANCED));
        away += 10u;
    }
    CHECK(ticks(CFG_STATE_TIMEOUT_TICKS - away, 0) & SEQ_EV_TIMEOUT);
}

static void test_a_full_cycle_returns_to_the_first_step_and_counts(void)
{
    static const cfg_state_t walk[] = {0, 2, 3, 1};
    unsigned i;
    uint8_t ev = 0;
    setup();
    seq_start(SEQ_DIR_PX, 0, 0);
    for (i = 0; i < 4u; i++) {
        CHECK_EQ(seq_target(), walk[i]);
        ev = ticks(CFG_HOLD_TICKS, walk[i]);
    }
    CHECK(ev & SEQ_EV_CYCLE);
    CHECK_EQ(seq_cycles(), 1);
    CHECK_EQ(seq_target(), 0);
}

static void test_start_begins_where_the_robot_is_on_the_walk(void)
{
    setup();
    CHECK_EQ(seq_start(SEQ_DIR_PX, 0, 3), SEQ_OK);
    CHECK_EQ(seq_step(), 2);
    CHECK_EQ(seq_target(), 3);
    CHECK_EQ(seq_start(SEQ_DIR_PX, 1, 3), SEQ_OK); /* 11 is not on 00 10: first step */
    CHECK_EQ(seq_step(), 0);
}

static void test_start_of_a_gait_that_does_not_exist_is_refused(void)
{
    setup();
    CHECK_EQ(seq_start(SEQ_DIR_MX, 0, 0), SEQ_ERR_NO_GAIT);
    CHECK_EQ(seq_start(SEQ_DIR_PX, 2, 0), SEQ_ERR_NO_GAIT);
    CHECK_EQ(seq_start(SEQ_DIR_LOADED, 0, 0), SEQ_ERR_NO_GAIT);
    CHECK_EQ(seq_start(7, 0, 0), SEQ_ERR_NO_GAIT);
    CHECK(!seq_running());
}

static void test_loaded_gait_accepts_open_and_closed_walks(void)
{
    static const cfg_state_t closed[] = {1, 3, 2, 0, 1};
    static const cfg_state_t open[] = {3, 0};
    setup();
    CHECK_EQ(seq_load(closed, 5, 0), SEQ_OK);
    CHECK_EQ(seq_gait_count(SEQ_DIR_LOADED), 1);
    CHECK_EQ(seq_start(SEQ_DIR_LOADED, 0, 0), SEQ_OK);
    CHECK_EQ(seq_target(), 0);
    CHECK_EQ(seq_step(), 3);
    ticks(CFG_HOLD_TICKS, 0);
    CHECK_EQ(seq_target(), 1); /* wrapped to the first step */
    seq_stop();
    CHECK_EQ(seq_load(open, 2, 0), SEQ_OK);
}

static void test_loaded_gait_too_long_or_too_short_is_refused(void)
{
    cfg_state_t walk[CFG_MAX_LOADED_STEPS + 1u];
    unsigned i;
    setup();
    for (i = 0; i < CFG_MAX_LOADED_STEPS + 1u; i++) {
        walk[i] = (cfg_state_t)((i % 2u) ? 2 : 0);
    }
    walk[CFG_MAX_LOADED_STEPS] = 1; /* not closed: 25 steps */
    CHECK_EQ(seq_load(walk, CFG_MAX_LOADED_STEPS + 1u, 0), SEQ_ERR_LENGTH);
    CHECK_EQ(seq_load(walk, CFG_MAX_LOADED_STEPS, 0), SEQ_OK);
    CHECK_EQ(seq_load(walk, 0, 0), SEQ_ERR_LENGTH);
}

/* A walk of one state (0, or 0 0 closed to it) is a state that follows itself: the forbidden
 * transition LOAD_GAIT documents at step 0 (definition.py), not a length (it was OUT_OF_RANGE). */
static void test_a_single_state_walk_is_a_forbidden_self_transition(void)
{
    static const cfg_state_t walk[3] = {2, 2, 2};
    uint16_t bad = 99;
    setup();
    CHECK_EQ(seq_load(walk, 1, &bad), SEQ_ERR_FORBIDDEN);
    CHECK_EQ(bad, 0);
    bad = 99;
    CHECK_EQ(seq_load(walk, 2, &bad), SEQ_ERR_FORBIDDEN); /* 2 2 closes to a single state */
    CHECK_EQ(bad, 0);
    bad = 99;
    CHECK_EQ(seq_load(walk, 3, &bad), SEQ_ERR_FORBIDDEN);
    CHECK_EQ(bad, 0);
    CHECK_EQ(seq_gait_count(SEQ_DIR_LOADED), 0);
}

static void test_loaded_gait_with_an_unknown_state_is_refused(void)
{
    cfg_state_t walk[2];
    uint16_t bad = 99;
    setup();
    walk[0] = 0;
    walk[1] = (cfg_state_t)CFG_N_STATES;
    CHECK_EQ(seq_load(walk, 2, &bad), SEQ_ERR_STATE);
    CHECK_EQ(bad, 1);
    CHECK_EQ(seq_gait_count(SEQ_DIR_LOADED), 0);
}

static void test_every_off_diagonal_transition_of_r1_is_allowed(void)
{
    cfg_state_t a, b;
    setup();
    for (a = 0; a < CFG_N_STATES; a++) {
        for (b = 0; b < CFG_N_STATES; b++) {
            CHECK_EQ(seq_allowed_transition(a, b), a != b);
        }
    }
}

int main(void)
{
    RUN(test_gait_table_holds_the_rendered_gaits);
    RUN(test_advances_to_the_next_step_after_target_held_for_hold_ticks);
    RUN(test_hold_restarts_when_the_state_leaves_the_target);
    RUN(test_reached_is_reported_once_per_step);
    RUN(test_holding_is_only_while_the_target_is_measured);
    RUN(test_step_not_completed_within_timeout_stops_with_a_timeout_event);
    RUN(test_a_target_held_longer_than_the_timeout_advances_without_a_timeout);
    RUN(test_time_away_from_the_target_adds_up_over_a_flickering_step);
    RUN(test_a_full_cycle_returns_to_the_first_step_and_counts);
    RUN(test_start_begins_where_the_robot_is_on_the_walk);
    RUN(test_start_of_a_gait_that_does_not_exist_is_refused);
    RUN(test_loaded_gait_accepts_open_and_closed_walks);
    RUN(test_loaded_gait_too_long_or_too_short_is_refused);
    RUN(test_a_single_state_walk_is_a_forbidden_self_transition);
    RUN(test_loaded_gait_with_an_unknown_state_is_refused);
    RUN(test_every_off_diagonal_transition_of_r1_is_allowed);
    return UNIT_EXIT();
}
