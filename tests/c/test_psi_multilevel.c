/* Host unit tests of multi-level limbs (k levels, k-1 thresholds). Config: limb 0 has
 * three levels, ψ* = -10° and 15°, hysteresis 4° (edges -12/-8 and 13/17); limb 1 two
 * levels, ψ* = 30°, hysteresis 2°. State index = mixed radix, first limb most significant. */
#include <math.h>

#include "psi.h"
#include "seq.h"
#include "unit.h"

#define PI_D 3.14159265358979323846

static int16_t ax_of(double deg) { return (int16_t)lround(8192.0 * sin(deg * PI_D / 180.0)); }
static int16_t az_of(double deg) { return (int16_t)lround(8192.0 * cos(deg * PI_D / 180.0)); }
static uint8_t classify(uint8_t prev, double deg) { return psi_classify(0, prev, ax_of(deg), az_of(deg)); }

static void test_three_level_limb_without_history_counts_upper_edges(void)
{
    psi_init();
    CHECK_EQ(psi_levels(0), 3);
    CHECK_EQ(classify(PSI_UNKNOWN, -20.0), 0);
    CHECK_EQ(classify(PSI_UNKNOWN, -9.0), 0);
    CHECK_EQ(classify(PSI_UNKNOWN, 0.0), 1);
    CHECK_EQ(classify(PSI_UNKNOWN, 16.0), 1);
    CHECK_EQ(classify(PSI_UNKNOWN, 20.0), 2);
}

static void test_three_level_limb_has_hysteresis_at_each_threshold(void)
{
    psi_init();
    CHECK_EQ(classify(2, 14.0), 2);
    CHECK_EQ(classify(2, 12.9), 1);
    CHECK_EQ(classify(1, 16.9), 1);
    CHECK_EQ(classify(1, 17.1), 2);
    CHECK_EQ(classify(1, -11.9), 1);
    CHECK_EQ(classify(1, -12.1), 0);
    CHECK_EQ(classify(0, -8.1), 0);
}

static void test_a_large_move_crosses_several_levels_in_one_sample(void)
{
    psi_init();
    CHECK_EQ(classify(0, 30.0), 2);
    CHECK_EQ(classify(2, -30.0), 0);
}

static void test_float_reference_sweep_of_three_levels(void)
{
    double deg;
    psi_init();
    for (deg = -60.0; deg <= 60.0; deg += 0.01) {
        double r = atan2((double)ax_of(deg), (double)az_of(deg)) * 180.0 / PI_D;
        uint8_t want = (uint8_t)((r >= -8.0) + (r >= 17.0));
        if (fabs(r + 8.0) < 0.01 || fabs(r - 17.0) < 0.01) {
            continue;
        }
        CHECK_EQ(classify(PSI_UNKNOWN, deg), want);
    }
}

static void test_state_index_is_mixed_radix_first_limb_most_significant(void)
{
    uint8_t levels[CFG_N_LIMBS];
    uint8_t want[CFG_N_LIMBS];
    cfg_state_t s;
    psi_init();
    CHECK_EQ(CFG_N_STATES, 6);
    levels[0] = 2;
    levels[1] = 1;
    CHECK_EQ(seq_state_index(levels), 5);
    for (s = 0; s < CFG_N_STATES; s++) {
        seq_state_levels(s, want);
        CHECK_EQ(want[0], s / 2);
        CHECK_EQ(want[1], s % 2);
        CHECK_EQ(seq_state_index(want), s);
    }
}

static void test_moving_a_threshold_into_its_neighbour_is_refused(void)
{
    psi_init();
    CHECK(psi_set_band(0, 1, -800, 400) != 0);  /* lower edge -10 overlaps [-12, -8] */
    CHECK(psi_set_band(0, 0, 1400, 400) != 0);  /* upper edge 16 overlaps [13, 17] */
    CHECK_EQ(psi_set_band(0, 1, 2500, 400), 0); /* [23, 27]: fine */
    CHECK_EQ(classify(1, 26.0), 1);
    CHECK_EQ(classify(1, 27.1), 2);
}

/* "multi": left ψ* −10° and 15°, bands 4° wide (test_firmware_core.py, _multi_level). */
static void test_a_width_one_band_refuses_changes_no_band(void)
{
    psi_init();
    CHECK(psi_set_hysteresis(0, 2600) != 0); /* 26°: out of 0..20° */
    CHECK_EQ(psi_set_band(0, 1, 500, 400), 0); /* ψ* 5°: the two 15° apart */
    CHECK(psi_set_hysteresis(0, 1600) != 0);   /* 16°: the bands would meet */
    CHECK_EQ(psi_hyst_cdeg(0, 0), 400);
    CHECK_EQ(psi_hyst_cdeg(0, 1), 400);
    CHECK(psi_set_hysteresis(1, 1600) == 0);   /* the one-threshold limb takes it */
    CHECK_EQ(psi_set_hysteresis(0, 1400), 0);  /* 14°: both take it */
    CHECK_EQ(psi_hyst_cdeg(0, 0), 1400);
    CHECK_EQ(psi_hyst_cdeg(0, 1), 1400);
    CHECK(psi_set_band(0, 1, 300, 1400) != 0); /* [−4°, 10°] meets [−17°, −3°] */
    CHECK(psi_set_hysteresis(2, 100) != 0);    /* no such limb */
}

int main(void)
{
    RUN(test_three_level_limb_without_history_counts_upper_edges);
    RUN(test_three_level_limb_has_hysteresis_at_each_threshold);
    RUN(test_a_large_move_crosses_several_levels_in_one_sample);
    RUN(test_float_reference_sweep_of_three_levels);
    RUN(test_state_index_is_mixed_radix_first_limb_most_significant);
    RUN(test_moving_a_threshold_into_its_neighbour_is_refused);
    RUN(test_a_width_one_band_refuses_changes_no_band);
    return UNIT_EXIT();
}
