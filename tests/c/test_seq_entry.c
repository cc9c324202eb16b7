/* Host unit tests of core/seq.c's entry from rest. Config: robots/inchworm-3.toml (only
 * one limb changes per transition), gait table +x: #0 = 011 111, #1 = 111 011; -x:
 * #0 = 001 101. From rest 000, 011 is two transitions away (000 001 011): the entry path. */
#include "seq.h"
#include "unit.h"

static uint8_t hold(cfg_state_t measured)
{
    uint8_t ev = 0;
    uint32_t n = CFG_HOLD_TICKS;
    while (n--) {
        ev = (uint8_t)(ev | seq_tick(measured));
    }
    return ev;
}

static void test_a_gait_off_rest_is_entered_through_allowed_transitions(void)
{
    seq_init();
    CHECK_EQ(seq_start(SEQ_DIR_PX, 0, 0), SEQ_OK);
    CHECK_EQ(seq_target(), 1); /* 001 first, not 011 (two limbs at once: not allowed) */
    CHECK_EQ(seq_step(), SEQ_STEP_ENTRY);
    CHECK(hold(1) & SEQ_EV_ADVANCED);
    CHECK_EQ(seq_target(), 3); /* the gait's step 0 */
    CHECK_EQ(seq_step(), 0);
    CHECK(hold(3) & SEQ_EV_ADVANCED);
    CHECK_EQ(seq_target(), 7);
    CHECK_EQ(seq_cycles(), 0);
}

static void test_the_entry_path_joins_the_gait_at_its_nearest_state(void)
{
    seq_init();
    CHECK_EQ(seq_start(SEQ_DIR_PX, 1, 0), SEQ_OK);
    CHECK_EQ(seq_target(), 1);
    CHECK(hold(1) & SEQ_EV_ADVANCED);
    CHECK_EQ(seq_target(), 3); /* 011 is the gait's step 1 */
    CHECK_EQ(seq_step(), 1);
    CHECK(hold(3) & SEQ_EV_CYCLE);
    CHECK_EQ(seq_target(), 7);
}

static void test_a_gait_one_transition_from_rest_starts_at_once(void)
{
    seq_init();
    CHECK_EQ(seq_start(SEQ_DIR_MX, 0, 0), SEQ_OK);
    CHECK_EQ(seq_target(), 1);
    CHECK_EQ(seq_step(), 0);
}

static void test_a_start_on_the_walk_or_off_rest_keeps_the_old_rule(void)
{
    seq_init();
    CHECK_EQ(seq_start(SEQ_DIR_PX, 0, 7), SEQ_OK); /* on the walk: from there */
    CHECK_EQ(seq_target(), 7);
    CHECK_EQ(seq_step(), 1);
    CHECK_EQ(seq_start(SEQ_DIR_PX, 0, 4), SEQ_OK); /* elsewhere: step 0 */
    CHECK_EQ(seq_target(), 3);
    CHECK_EQ(seq_step(), 0);
}

/* seq.h, SEQ_CLOCK_PAUSE (built for three or more limbs): ticks with the clock paused (a fall
 * still coming down) do not count toward the step timeout; the others do, before and after. */
static void test_a_paused_clock_does_not_count_toward_the_step_timeout(void)
{
    uint32_t k, n = 100u;
    uint8_t ev = 0;
    seq_init();
    seq_set_timeout(n);
    CHECK_EQ(seq_start(SEQ_DIR_PX, 0, 0), SEQ_OK); /* target 001, measured 000: away */
    for (k = 0; k < n / 2u; k++) {
        ev = (uint8_t)(ev | seq_tick(0));
    }
    seq_pause_clock(1);
    for (k = 0; k < 10u * n; k++) {
        ev = (uint8_t)(ev | seq_tick(0));
    }
    CHECK(!(ev & SEQ_EV_TIMEOUT));
    CHECK(seq_running());
    seq_pause_clock(0);
    for (k = 0; k + 1u < n - n / 2u; k++) {
        ev = (uint8_t)(ev | seq_tick(0));
    }
    CHECK(!(ev & SEQ_EV_TIMEOUT));
    CHECK(seq_tick(0) & SEQ_EV_TIMEOUT); /* the n-th unpaused tick away */
    CHECK(!seq_running());
}

int main(void)
{
    RUN(test_a_gait_off_rest_is_entered_through_allowed_transitions);
    RUN(test_the_entry_path_joins_the_gait_at_its_nearest_state);
    RUN(test_a_gait_one_transition_from_rest_starts_at_once);
    RUN(test_a_start_on_the_walk_or_off_rest_keeps_the_old_rule);
    RUN(test_a_paused_clock_does_not_count_toward_the_step_timeout);
    return UNIT_EXIT();
}
