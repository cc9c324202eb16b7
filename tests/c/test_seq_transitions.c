/* Host unit tests of LOAD_GAIT checks against a robot with forbidden transitions: the
 * paper's R1 with one actuator (00->01, 00->11, 10->01, 11->00, 11->01 and every
 * transition out of 01 are forbidden). Also the edge-list form used for big robots is
 * exercised by test_seq_edges (same source, CFG_TRANS_BITMAP 0). */
#include "psi.h"
#include "seq.h"
#include "unit.h"

static const uint8_t allowed[4][4] = {
    {0, 0, 1, 0},
    {0, 0, 0, 0},
    {1, 0, 0, 1},
    {0, 0, 1, 0},
};

static void test_allowed_transitions_match_the_robot_file(void)
{
    cfg_state_t a, b;
    psi_init();
    seq_init();
    for (a = 0; a < 4u; a++) {
        for (b = 0; b < 4u; b++) {
            CHECK_EQ(seq_allowed_transition(a, b), allowed[a][b]);
        }
    }
    CHECK_EQ(seq_allowed_transition(0, (cfg_state_t)CFG_N_STATES), 0);
}

static void test_load_gait_rejects_a_forbidden_transition_and_names_its_step(void)
{
    static const cfg_state_t bad_middle[] = {0, 2, 3, 1};
    static const cfg_state_t bad_wrap[] = {0, 2, 3};
    uint16_t bad = 99;
    seq_init();
    CHECK_EQ(seq_load(bad_middle, 4, &bad), SEQ_ERR_FORBIDDEN);
    CHECK_EQ(bad, 2); /* 11 -> 01 */
    CHECK_EQ(seq_load(bad_wrap, 3, &bad), SEQ_ERR_FORBIDDEN);
    CHECK_EQ(bad, 2); /* 11 -> 00, closing the walk */
    CHECK_EQ(seq_gait_count(SEQ_DIR_LOADED), 0);
}

static void test_load_gait_accepts_a_walk_over_allowed_transitions(void)
{
    static const cfg_state_t ok[] = {0, 2, 3, 2, 0};
    seq_init();
    CHECK_EQ(seq_load(ok, 5, 0), SEQ_OK);
    CHECK_EQ(seq_gait_count(SEQ_DIR_LOADED), 1);
}

static void test_direction_without_a_gait_has_none(void)
{
    seq_init();
    CHECK_EQ(seq_gait_count(SEQ_DIR_MX), 0);
    CHECK_EQ(seq_start(SEQ_DIR_MX, 0, 0), SEQ_ERR_NO_GAIT);
}

int main(void)
{
    RUN(test_allowed_transitions_match_the_robot_file);
    RUN(test_load_gait_rejects_a_forbidden_transition_and_names_its_step);
    RUN(test_load_gait_accepts_a_walk_over_allowed_transitions);
    RUN(test_direction_without_a_gait_has_none);
    return UNIT_EXIT();
}
