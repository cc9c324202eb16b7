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

/* Seven two-level limbs in 8-bit states: seq_state_levels takes the binary digits (seq.c).
 * Oracle: the mixed-radix subtraction it replaces, for every 8-bit value, past the last
 * state too (limb 0 then takes every higher bit); and the round trip through
 * seq_state_index for every state. */
static void test_binary_state_digits_match_the_subtraction_for_every_byte(void)
{
    uint16_t st, v, place;
    uint8_t got[CFG_N_LIMBS], i, d;
    CHECK(PSI_UNIFORM_LEVELS && CFG_MAX_LEVELS == 2u && CFG_STATE_BYTES == 1);
    psi_init();
    for (st = 0; st < 256u; st++) {
        seq_state_levels((cfg_state_t)st, got);
        v = st;
        for (i = 0; i < CFG_N_LIMBS; i++) {
            place = (uint16_t)(1u << (CFG_N_LIMBS - 1u - i));
            for (d = 0; v >= place && d < 0xFFu; d++) {
                v = (uint16_t)(v - place);
            }
            CHECK_EQ(got[i], d);
        }
        if (st < CFG_N_STATES) {
            CHECK_EQ(seq_state_index(got), st);
        }
    }
}

int main(void)
{
    RUN(test_big_robot_allowed_transitions_match_the_table);
    RUN(test_binary_state_digits_match_the_subtraction_for_every_byte);
    return UNIT_EXIT();
}
