/* Host unit test of the allowed-transition check for a robot too big for a bitmap
 * (128 states: a sorted key list, binary search). The robot allows a -> a+1 (mod 128)
 * and a -> 3a+7 (mod 128), as rendered by tests/test_firmware_core.py. */
#include "psi.h"
#include "seq.h"
#include "unit.h"

static void test_big_robot_allowed_transitions_match_the_table(void)
{
    uint32_t a, b;
    CHECK_EQ(CFG_TRANS_BITMAP, 0);
    CHECK_EQ(CFG_N_STATES, 128);
    psi_init();
    seq_init();
    for (a = 0; a < 128u; a++) {
        for (b = 0; b < 128u; b++) {
            uint8_t want = (uint8_t)(a != b && (b == (a + 1u) % 128u || b == (3u * a + 7u) % 128u));
            CHECK_EQ(seq_allowed_transition((cfg_state_t)a, (cfg_state_t)b), want);
        }
    }
}

int main(void)
{
    RUN(test_big_robot_allowed_transitions_match_the_table);
    return UNIT_EXIT();
}
