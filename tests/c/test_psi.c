/* Host unit tests of core/psi.c (ψ classifier, hysteresis, debounce) and core/angle.c (integer
 * sin/cos and atan2).
 * Built by tests/test_firmware_core.py against the rendered config of a paper-R1-like
 * robot: ψ* = 20°, hysteresis 2° (band edges 19° and 21°), debounce CFG_DEBOUNCE_TICKS. */
#include <math.h>

#include "angle.h"
#include "psi.h"
#include "unit.h"

#define PI_D 3.14159265358979323846
#define G 8192.0 /* LSB per g at ±4 g */

static int16_t ax_of(double deg) { return (int16_t)lround(G * sin(deg * PI_D / 180.0)); }
static int16_t az_of(double deg) { return (int16_t)lround(G * cos(deg * PI_D / 180.0)); }
static double ref_deg(int16_t ax, int16_t az) { return atan2((double)ax, (double)az) * 180.0 / PI_D; }

/* Float reference of the two-edge hysteresis classifier for one threshold. */
static uint8_t ref_level(uint8_t prev, double psi, double lo, double hi)
{
    if (prev == 1u) {
        return psi < lo ? 0u : 1u;
    }
    return psi >= hi ? 1u : 0u;
}

static void sweep_against_reference(double lo, double hi)
{
    double deg;
    for (deg = -89.9; deg <= 89.9; deg += 0.01) {
        int16_t ax = ax_of(deg), az = az_of(deg);
        double r = ref_deg(ax, az);
        uint8_t prev;
        if (fabs(r - lo) < 0.01 || fabs(r - hi) < 0.01) {
            continue; /* within the Q14 constants' resolution of an edge */
        }
        for (prev = 0; prev <= 1u; prev++) {
            if (psi_classify(0, prev, ax, az) != ref_level(prev, r, lo, hi)) {
                printf("  at %.3f deg (ref %.4f) prev %u: got %u\n", deg, r, prev, psi_classify(0, prev, ax, az));
            }
            CHECK_EQ(psi_classify(0, prev, ax, az), ref_level(prev, r, lo, hi));
        }
        CHECK_EQ(psi_classify(0, PSI_UNKNOWN, ax, az), ref_level(0, r, lo, hi));
    }
}

static void test_classifier_agrees_with_float_atan2_across_angles(void)
{
    psi_init();
    sweep_against_reference(19.0, 21.0);
}

static void test_level_holds_inside_the_hysteresis_band(void)
{
    psi_init();
    CHECK_EQ(psi_classify(0, 1, ax_of(19.5), az_of(19.5)), 1);
    CHECK_EQ(psi_classify(0, 0, ax_of(20.5), az_of(20.5)), 0);
    CHECK_EQ(psi_classify(0, 0, ax_of(21.05), az_of(21.05)), 1);
    CHECK_EQ(psi_classify(0, 1, ax_of(18.95), az_of(18.95)), 0);
}

static void test_classifier_scales_with_any_gravity_magnitude(void)
{
    /* Only the direction matters: ±2 g or ±16 g full scale give the same levels. */
    double m;
    psi_init();
    for (m = 500.0; m < 32000.0; m *= 1.7) {
        int16_t ax = (int16_t)lround(m * sin(25.0 * PI_D / 180.0));
        int16_t az = (int16_t)lround(m * cos(25.0 * PI_D / 180.0));
        CHECK_EQ(psi_classify(0, 0, ax, az), 1);
        ax = (int16_t)lround(m * sin(15.0 * PI_D / 180.0));
        az = (int16_t)lround(m * cos(15.0 * PI_D / 180.0));
        CHECK_EQ(psi_classify(0, 1, ax, az), 0);
    }
}

static void test_debounce_reports_a_change_after_n_consecutive_samples(void)
{
    uint16_t i;
    psi_init();
    CHECK_EQ(psi_level(0), PSI_UNKNOWN);
    CHECK_EQ(psi_update(0, ax_of(0.0), az_of(0.0)), 0); /* first sample: no history to debounce */
    for (i = 1; i < CFG_DEBOUNCE_TICKS; i++) {
        CHECK_EQ(psi_update(0, ax_of(25.0), az_of(25.0)), 0);
    }
    CHECK_EQ(psi_update(0, ax_of(25.0), az_of(25.0)), 1);
}

static void test_debounce_ignores_a_glitch_shorter_than_n_samples(void)
{
    uint16_t i, round;
    psi_init();
    psi_update(0, ax_of(0.0), az_of(0.0));
    for (round = 0; round < 5; round++) {
        for (i = 1; i < CFG_DEBOUNCE_TICKS; i++) {
            CHECK_EQ(psi_update(0, ax_of(25.0), az_of(25.0)), 0);
        }
        CHECK_EQ(psi_update(0, ax_of(0.0), az_of(0.0)), 0);
    }
}

static void test_debounce_one_reports_every_change_at_once(void)
{
    psi_init();
    psi_set_debounce(1);
    psi_update(0, ax_of(0.0), az_of(0.0));
    CHECK_EQ(psi_update(0, ax_of(25.0), az_of(25.0)), 1);
    CHECK_EQ(psi_update(0, ax_of(0.0), az_of(0.0)), 0);
}

static void test_limbs_are_classified_independently(void)
{
    psi_init();
    psi_set_debounce(1);
    psi_update(0, ax_of(30.0), az_of(30.0));
    psi_update(1, ax_of(5.0), az_of(5.0));
    CHECK_EQ(psi_level(0), 1);
    CHECK_EQ(psi_level(1), 0);
}

static void test_integer_atan2_is_within_0_02_deg_of_float_all_round(void)
{
    static const double mags[] = {300.0, 8192.0, 16384.0, 32000.0};
    double worst = 0.0;
    unsigned k;
    for (k = 0; k < sizeof mags / sizeof mags[0]; k++) {
        double deg;
        for (deg = -179.99; deg <= 180.0; deg += 0.173) {
            int16_t ax = (int16_t)lround(mags[k] * sin(deg * PI_D / 180.0));
            int16_t az = (int16_t)lround(mags[k] * cos(deg * PI_D / 180.0));
            double err = angle_atan2_cdeg(ax, az) - ref_deg(ax, az) * 100.0;
            if (err > 18000.0) {
                err -= 36000.0;
            } else if (err < -18000.0) {
                err += 36000.0;
            }
            if (fabs(err) > worst) {
                worst = fabs(err);
            }
        }
    }
    printf("  worst atan2 error %.2f cdeg\n", worst);
    CHECK(worst <= 2.0);
}

/* angle_atan2_cdeg as it was before its atan table became 8-bit steps (issue 11): the oracle
 * for the exhaustive test below. */
static const int16_t old_atan_tab[33] = {
    0,    179,  358,  536,  713,  888,  1062, 1234, 1404, 1571, 1735, 1897, 2056, 2211, 2363, 2511, 2657,
    2798, 2936, 3070, 3201, 3327, 3451, 3571, 3687, 3800, 3909, 4016, 4119, 4218, 4315, 4409, 4500,
};

static int16_t old_atan_frac(uint16_t n, uint16_t d)
{
    uint16_t r = 0, rem = n, i, f;
    uint8_t k;
    int16_t a, b;
    if (n >= d) {
        r = 32768u;
    } else {
        for (k = 0; k < 15u; k++) {
            rem = (uint16_t)(rem << 1);
            r = (uint16_t)(r << 1);
            if (rem >= d) {
                rem = (uint16_t)(rem - d);
                r |= 1u;
            }
        }
    }
    i = (uint16_t)(r >> 10);
    f = (uint16_t)(r & 1023u);
    if (i >= 32u) {
        return old_atan_tab[32];
    }
    a = old_atan_tab[i];
    b = old_atan_tab[i + 1u];
    return (int16_t)(a + (int16_t)(((uint32_t)(uint16_t)(b - a) * f + 512u) >> 10));
}

static int16_t old_centideg(int16_t ax, int16_t az)
{
    uint16_t x = ax < 0 ? (uint16_t)(0u - (uint16_t)ax) : (uint16_t)ax;
    uint16_t z = az < 0 ? (uint16_t)(0u - (uint16_t)az) : (uint16_t)az;
    int16_t a;
    if (x == 0u && z == 0u) {
        return 0;
    }
    a = (x <= z) ? old_atan_frac(x, z) : (int16_t)(9000 - old_atan_frac(z, x));
    if (az < 0) {
        a = (int16_t)(18000 - a);
    }
    return ax < 0 ? (int16_t)-a : a;
}

/* Every ax against a few az, both ways round: with |az| = 32768 the Q15 ratio takes every
 * value 0..32768, so every table step and every fraction is checked. */
static void test_atan_steps_give_the_old_table_result_for_every_ratio(void)
{
    static const int16_t others[] = {-32768, 32767, 1000, -7, 0};
    long bad = 0;
    unsigned k;
    int32_t v;
    for (k = 0; k < sizeof others / sizeof others[0]; k++) {
        for (v = -32768; v <= 32767; v++) {
            bad += angle_atan2_cdeg((int16_t)v, others[k]) != old_centideg((int16_t)v, others[k]);
            bad += angle_atan2_cdeg(others[k], (int16_t)v) != old_centideg(others[k], (int16_t)v);
        }
    }
    CHECK_EQ(bad, 0);
}

static void test_integer_sin_cos_match_float_within_2_lsb(void)
{
    int32_t cd;
    for (cd = -9000; cd <= 9000; cd++) { /* every 0.01° */
        double r = cd / 100.0 * PI_D / 180.0;
        CHECK(labs((long)angle_sin_q14((int16_t)cd) - lround(sin(r) * 16384.0)) <= 2);
        CHECK(labs((long)angle_cos_q14((int16_t)cd) - lround(cos(r) * 16384.0)) <= 2);
    }
}

static void test_moved_threshold_classifies_like_a_rendered_one(void)
{
    psi_init();
    CHECK_EQ(psi_set_band(0, 0, 3000, 200), 0);
    CHECK_EQ(psi_star_cdeg(0, 0), 3000);
    sweep_against_reference(29.0, 31.0);
    CHECK_EQ(psi_set_band(0, 0, -4550, 50), 0);
    sweep_against_reference(-45.75, -45.25);
}

static void test_threshold_band_reaching_90_deg_is_refused(void)
{
    psi_init();
    CHECK(psi_set_band(0, 0, 8950, 200) != 0);
    CHECK(psi_set_band(0, 0, 2000, 2500) != 0);
    CHECK(psi_set_band(0, 1, 2000, 200) != 0); /* a two-level limb has one threshold */
    CHECK(psi_set_band(CFG_N_LIMBS, 0, 2000, 200) != 0);
    sweep_against_reference(19.0, 21.0); /* unchanged */
}

static void put(uint8_t limb, double deg)
{
    psi_update(limb, ax_of(deg), az_of(deg));
}

/* Float reference of psi_to_go_cdeg: the distance rounded up to the next edge. */
static int16_t ref_to_go(double d, uint8_t rising)
{
    static const int16_t edges[PSI_PROGRESS_EDGES] = PSI_PROGRESS_CDEG;
    uint8_t k, n = rising ? PSI_PROGRESS_EDGES : PSI_FALL_EDGES;
    if (d <= 0.0) {
        return 0;
    }
    for (k = 0; k < n; k++) {
        if (d * 100.0 <= edges[k]) {
            return edges[k];
        }
    }
    return PSI_FAR;
}

static void test_distance_to_a_crossing_agrees_with_float_without_atan(void)
{
    double deg;
    psi_init();
    psi_set_debounce(1);
    for (deg = -30.0; deg <= 60.0; deg += 0.037) {
        int16_t ax = ax_of(deg), az = az_of(deg);
        double r = ref_deg(ax, az);
        uint8_t k, near = fabs(21.0 - r) * 100.0 < 1.0 || fabs(r - 19.0) * 100.0 < 1.0;
        static const int16_t edges[PSI_PROGRESS_EDGES] = PSI_PROGRESS_CDEG;
        for (k = 0; k < PSI_PROGRESS_EDGES; k++) {
            near |= fabs((21.0 - r) * 100.0 - edges[k]) < 1.0 || fabs((r - 19.0) * 100.0 - edges[k]) < 1.0;
        }
        if (near) {
            continue; /* within the Q14 constants' resolution of an edge */
        }
        psi_reset();
        psi_update(0, ax, az);
        CHECK_EQ(psi_to_go_cdeg(0, 0, 1), ref_to_go(21.0 - r, 1));
        CHECK_EQ(psi_to_go_cdeg(0, 0, 0), ref_to_go(r - 19.0, 0));
    }
}

static void test_settled_needs_the_margins_for_a_dwell_and_keeps_until_a_dwell_past_the_band_edge(void)
{
    /* hold edge 21° + margin, settle edge 19° − margin (CFG_HOLD_MARGIN_CDEG) */
    double m = CFG_HOLD_MARGIN_CDEG / 100.0;
    psi_init();
    psi_set_debounce(3);
    put(0, 30.0); /* first sample: level 1 at once, clear of the margin: 1 of 3 */
    CHECK_EQ(psi_level(0), 1);
    CHECK_EQ(psi_settled(0), 0);
    put(0, 30.0);
    CHECK_EQ(psi_settled(0), 0);
    put(0, 30.0);
    CHECK_EQ(psi_settled(0), 1); /* dwell: 3 samples */
    put(0, 21.0 + m / 2.0);      /* inside the margin but above the band: stays settled */
    CHECK_EQ(psi_settled(0), 1);
    put(0, 20.5); /* below the band's upper edge: one noisy sample is not an excursion */
    CHECK_EQ(psi_settled(0), 1);
    put(0, 21.0 + m / 2.0); /* back inside: the count of samples outside restarts */
    put(0, 20.5);
    put(0, 20.5);
    CHECK_EQ(psi_settled(0), 1);
    put(0, 20.5); /* outside for the dwell (3 samples in a row): unsettled (still level 1) */
    CHECK_EQ(psi_level(0), 1);
    CHECK_EQ(psi_settled(0), 0);
    put(0, 21.0 + m / 2.0); /* back inside the margin: not enough to settle again */
    put(0, 21.0 + m / 2.0);
    put(0, 21.0 + m / 2.0);
    CHECK_EQ(psi_settled(0), 0);
    psi_relax(0, 1); /* relaxed: above the band edge is enough */
    put(0, 21.0 + m / 2.0);
    put(0, 21.0 + m / 2.0);
    put(0, 21.0 + m / 2.0);
    CHECK_EQ(psi_settled(0), 1);
    psi_relax(0, 0);
    put(0, 5.0); /* level change (after the debounce): unsettled at once */
    put(0, 5.0);
    put(0, 5.0);
    CHECK_EQ(psi_level(0), 0);
    CHECK_EQ(psi_settled(0), 0);
    put(0, 19.0 - m / 2.0); /* level 0 inside the settle margin: never settles */
    put(0, 19.0 - m / 2.0);
    put(0, 19.0 - m / 2.0);
    put(0, 19.0 - m / 2.0);
    CHECK_EQ(psi_settled(0), 0);
}

int main(void)
{
    RUN(test_classifier_agrees_with_float_atan2_across_angles);
    RUN(test_level_holds_inside_the_hysteresis_band);
    RUN(test_classifier_scales_with_any_gravity_magnitude);
    RUN(test_debounce_reports_a_change_after_n_consecutive_samples);
    RUN(test_debounce_ignores_a_glitch_shorter_than_n_samples);
    RUN(test_debounce_one_reports_every_change_at_once);
    RUN(test_limbs_are_classified_independently);
    RUN(test_integer_atan2_is_within_0_02_deg_of_float_all_round);
    RUN(test_atan_steps_give_the_old_table_result_for_every_ratio);
    RUN(test_integer_sin_cos_match_float_within_2_lsb);
    RUN(test_moved_threshold_classifies_like_a_rendered_one);
    RUN(test_threshold_band_reaching_90_deg_is_refused);
    RUN(test_distance_to_a_crossing_agrees_with_float_without_atan);
    RUN(test_settled_needs_the_margins_for_a_dwell_and_keeps_until_a_dwell_past_the_band_edge);
    return UNIT_EXIT();
}
