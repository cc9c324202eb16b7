/* psi.c - see psi.h. */
#include "psi.h"

#include <string.h>

#include "angle.h"
#include "rom.h"

static const uint8_t limb_levels[CFG_N_LIMBS] ROM = CFG_LIMB_LEVELS;
static const int16_t psi_star_rom[CFG_N_LIMBS][CFG_MAX_THRESHOLDS] ROM = CFG_LIMB_PSI_STAR_CDEG;
static const int16_t hyst_rom[CFG_N_LIMBS] ROM = CFG_LIMB_HYST_CDEG;

/* Per limb and threshold, in one record (an 8-bit MCU computes its address once): its
 * edges, the threshold in use (SET_PARAM may move it) and its angles in 0.01°. */
#define E_UPPER 0u  /* the band's upper edge ψ* + h/2 (= PSI_EDGE_UPPER) */
#define E_LOWER 1u  /* its lower edge ψ* − h/2 (= PSI_EDGE_LOWER) */
#define E_HOLD 2u   /* the hold edge (below) */
#define E_TOP 3u    /* the hold top */
#define E_SETTLE 4u /* the settle edge */
typedef struct {
    int16_t e[5][2];          /* {cos, sin} Q14 of each E_* edge */
    int16_t lo, hi;           /* band edges ψ* − h/2, ψ* + h/2 */
    int16_t star, hyst;       /* ψ* and the band width */
} band_t;
typedef char edge_numbers_match_psi_h[PSI_EDGE_UPPER == E_UPPER && PSI_EDGE_LOWER == E_LOWER ? 1 : -1];
static band_t bands[CFG_N_LIMBS][CFG_MAX_THRESHOLDS];

/* Holding a level, the controller keeps ψ above the band's upper edge plus this margin:
 * the SMA's thermal lag makes ψ dip after each heating pulse, and a dip below ψ* would
 * change the friction state for real even if the hysteresis band hides it. */
#ifndef CFG_HOLD_MARGIN_CDEG
#define CFG_HOLD_MARGIN_CDEG 0
#endif
/* band_t's E_HOLD, E_TOP and E_SETTLE: {cos, sin} Q14 of the hold edge ψ* + h/2 + margin,
 * the hold top (the hold edge plus PSI_HOLD_BAND_CDEG) and the settle edge ψ* − h/2 − margin. */
/* Per progress distance d of PSI_PROGRESS_CDEG: d, then {cos d, sin d} in Q14 (round(16384·cos d),
 * round(16384·sin d)). The progress edges are the band edge turned by d (psi_to_go_cdeg), so no
 * per-limb table of them is kept (RAM: 60 B per limb and threshold). */
static const int16_t progress[PSI_PROGRESS_EDGES][3] ROM = {
    {100, 16382, 286},   {200, 16374, 572},   {300, 16362, 857},   {400, 16344, 1143},  {500, 16322, 1428},
    {600, 16294, 1713},  {800, 16225, 2280},  {1000, 16135, 2845}, {1200, 16026, 3406}, {1500, 15826, 4240},
    {2000, 15396, 5604}, {2500, 14849, 6924}, {3000, 14189, 8192},
};
typedef char progress_matches_psi_h[PSI_PROGRESS_EDGES == 13 && PSI_FALL_EDGES <= 13 ? 1 : -1];

#if defined(__GNUC__)
#define NOINLINE __attribute__((noinline)) /* many callers: one copy on the 8-bit targets */
#else
#define NOINLINE
#endif

/* The record of threshold `thr` of `limb`: one copy of the address arithmetic. */
static NOINLINE band_t *band(uint8_t limb, uint8_t thr)
{
    return &bands[limb][CFG_MAX_THRESHOLDS > 1u ? thr : 0u]; /* one threshold per limb: thr is 0 */
}

/* {cos, sin} Q14 of `cdeg`, −9000 < cdeg < 9000. */
static void edge_of(int16_t cdeg, int16_t edge[2])
{
    edge[0] = angle_cos_q14(cdeg);
    edge[1] = angle_sin_q14(cdeg);
}

#ifdef CFG_LIMB_STROKE_CDEG
/* Per limb, 0.01°: where it is held on its top level (robot file [[limb]] stroke_deg),
 * PSI_NO_STROKE: just past its top band (CFG_HOLD_MARGIN_CDEG). */
static const int16_t stroke_rom[CFG_N_LIMBS] ROM = CFG_LIMB_STROKE_CDEG;

int16_t psi_upper_cdeg(uint8_t limb, uint8_t thr)
{
    return band(limb, thr)->hi;
}

int16_t psi_stroke_cdeg(uint8_t limb)
{
    int16_t s = ROM_I16(&stroke_rom[limb]);
    /* a SET_PARAM that moved the top ψ* up to the stroke or past it turns the stroke off */
    return s != PSI_NO_STROKE && s > psi_upper_cdeg(limb, (uint8_t)(psi_levels(limb) - 2u)) ? s : PSI_NO_STROKE;
}

/* The hold edge and hold top of `limb`'s top threshold `thr` at its stroke, if it has one. */
static void set_stroke(uint8_t limb, uint8_t thr)
{
    band_t *b = band(limb, thr);
    int16_t s = psi_stroke_cdeg(limb);
    if (s != PSI_NO_STROKE && thr + 2u == psi_levels(limb)) {
        edge_of(s, b->e[E_HOLD]);
        edge_of((int16_t)(s + PSI_HOLD_BAND_CDEG), b->e[E_TOP]);
    }
}

#define SET_STROKE(limb, thr) set_stroke(limb, thr)
#else
#define SET_STROKE(limb, thr) ((void)0)
#endif

/* The band's lower edge: ψ* less half the width (0 ≤ h ≤ 2000: robot_limbs.py, psi_set_band; /2 as
 * a shift); the upper edge is lo + h. One copy for both callers. */
#if defined(__GNUC__)
__attribute__((noinline))
#endif
static int16_t band_lo(int16_t star, int16_t hyst)
{
    return (int16_t)(star - (int16_t)((uint16_t)hyst >> 1));
}

/* Threshold ψ* with band width h (both in range) into `b`: its band edges in 0.01° and the
 * {cos, sin} of every E_* edge: the band's upper and lower edges, and the hold, hold-top
 * and settle edges (those clamped to ±89°). One computation for the rendered thresholds
 * (psi_init) and moved ones (psi_set_band): an edge is within 2 LSB of its exact Q14 value. */
static void set_angles(band_t *b, int16_t star, int16_t hyst)
{
    /* per E_* edge: its offset from the band edge it is measured from */
    static const int16_t offset[5] ROM = {0, 0, CFG_HOLD_MARGIN_CDEG, CFG_HOLD_MARGIN_CDEG + PSI_HOLD_BAND_CDEG,
                                          -CFG_HOLD_MARGIN_CDEG};
    uint8_t k;
    b->star = star;
    b->hyst = hyst;
    b->lo = band_lo(star, hyst);
    b->hi = (int16_t)(b->lo + hyst);
    for (k = 0; k < 5u; k++) {
        /* the upper, hold and top edges above the upper band edge, the others below the lower */
        int16_t cdeg = (int16_t)((k == E_LOWER || k == E_SETTLE ? b->lo : b->hi) + ROM_I16(&offset[k]));
        if (k >= E_HOLD) {
            cdeg = cdeg > 8900 ? 8900 : cdeg < -8900 ? -8900 : cdeg;
        }
        edge_of(cdeg, b->e[k]);
    }
}

/* One comparison against a Q14 edge {cos θ, sin θ}: ψ ≥ θ. Out of line too (many callers). */
#if defined(__GNUC__)
__attribute__((noinline))
#endif
static uint8_t at_or_above(const int16_t *edge, int16_t ax, int16_t az)
{
    return angle_dot_q14(edge[0], edge[1], ax, az) >= 0;
}

typedef struct {
    int16_t ax, az;  /* last sample */
    uint8_t hyst;    /* hysteresis level, PSI_UNKNOWN before the first sample */
    uint8_t level;   /* debounced level */
    uint16_t count;  /* samples the hysteresis level has differed from `level` */
    uint8_t settled; /* latched: clear of the margins for `debounce` samples (psi.h) */
    uint8_t relaxed; /* settle on the band edges instead of the margin edges */
    uint16_t dwell;  /* samples clear of the margins while not yet settled */
#if PSI_IN_LEVEL
    uint8_t in_level; /* settle on the level's own lower band edge (psi_settle_in_level) */
#endif
#ifdef CFG_LIMB_STROKE_CDEG
    int16_t cdeg;    /* ψ of the last sample in 0.01° once computed (the stroke rules ask for it */
    uint8_t fresh;   /* several times a tick: one atan2 per sample on the 8-bit targets) */
#endif
    int16_t fx, fz;  /* the samples halved (no int16 overflow), smoothed: 1/16 of each new one */
} limb_state_t;

static limb_state_t limbs[CFG_N_LIMBS];
static uint16_t debounce; /* set by psi_init (no initial value: no .data bytes in flash) */

/* The last sample of `limb` against edge `e` (E_*) of threshold `thr`: ψ ≥ the edge. */
static uint8_t last_above(uint8_t limb, uint8_t thr, uint8_t e)
{
    const limb_state_t *l = &limbs[limb];
    return at_or_above(band(limb, thr)->e[e], l->ax, l->az);
}

void psi_reset(void)
{
    uint8_t i;
    memset(limbs, 0, sizeof limbs);
    for (i = 0; i < CFG_N_LIMBS; i++) {
        limbs[i].hyst = PSI_UNKNOWN;
        limbs[i].level = PSI_UNKNOWN;
    }
}

void psi_init(void)
{
    uint8_t i, j;
    for (i = 0; i < CFG_N_LIMBS; i++) {
        for (j = 0; j < CFG_MAX_THRESHOLDS; j++) {
            set_angles(band(i, j), ROM_I16(&psi_star_rom[i][j]), ROM_I16(&hyst_rom[i]));
            SET_STROKE(i, j);
        }
    }
    debounce = CFG_DEBOUNCE_TICKS;
    psi_reset();
}

/* The edges of a band ψ* ± h/2 (0.01°) into lo/hi: 0, or -1 when h is outside 0..2000 or
 * the band leaves (−90°, 90°). The one place these rules live (psi_set_band, psi_set_hysteresis). */
static int8_t band_edges(int16_t star, int16_t hyst, int16_t *lo, int16_t *hi)
{
    if (hyst < 0 || hyst > 2000 || star <= -9000 || star >= 9000) {
        return -1;
    }
    *lo = band_lo(star, hyst);
    *hi = (int16_t)(*lo + hyst);
    return (int8_t)(*lo <= -9000 || *hi >= 9000 ? -1 : 0);
}

int8_t psi_set_band(uint8_t limb, uint8_t thr, int16_t psi_star_cdeg, int16_t hyst_cdeg)
{
    int16_t lo, hi;
    band_t *b;
    if (limb >= CFG_N_LIMBS || thr >= CFG_MAX_THRESHOLDS || thr + 1u >= psi_levels(limb) ||
        band_edges(psi_star_cdeg, hyst_cdeg, &lo, &hi) != 0) {
        return -1;
    }
    b = band(limb, thr);
    if (thr > 0u && lo <= b[-1].hi) {
        return -1;
    }
    if (thr + 1u < CFG_MAX_THRESHOLDS && thr + 2u < psi_levels(limb) && hi >= b[1].lo) {
        return -1;
    }
    set_angles(b, psi_star_cdeg, hyst_cdeg);
    SET_STROKE(limb, thr);
    return 0;
}

int8_t psi_set_hysteresis(uint8_t limb, int16_t hyst_cdeg)
{
#if CFG_MAX_THRESHOLDS == 1u
    /* One threshold a limb (every limb has 2 levels, robot_limbs.py): its one band moved to its own
     * ψ* with the new width is exactly what psi_set_band checks and computes (R1 on the Nano
     * 42 B smaller than the loops below). */
    return limb < CFG_N_LIMBS ? psi_set_band(limb, 0, band(limb, 0)->star, hyst_cdeg) : (int8_t)-1;
#else
    uint8_t i, n;
    int16_t lo, hi, prev_hi = 0;
    if (limb >= CFG_N_LIMBS) {
        return -1;
    }
    n = (uint8_t)(psi_levels(limb) - 1u);
    for (i = 0; i < n; i++) { /* every band first: a width one band refuses changes none */
        if (band_edges(band(limb, i)->star, hyst_cdeg, &lo, &hi) != 0 || (i > 0u && lo <= prev_hi)) {
            return -1;
        }
        prev_hi = hi;
    }
    for (i = 0; i < n; i++) {
        band_t *b = band(limb, i);
        set_angles(b, b->star, hyst_cdeg);
        SET_STROKE(limb, i);
    }
    return 0;
#endif
}

int16_t psi_star_cdeg(uint8_t limb, uint8_t thr)
{
    return band(limb, thr)->star;
}

int16_t psi_hyst_cdeg(uint8_t limb, uint8_t thr)
{
    return band(limb, thr)->hyst;
}

void psi_set_debounce(uint16_t samples)
{
    debounce = samples ? samples : 1u;
}

uint8_t psi_levels(uint8_t limb)
{
    if (PSI_UNIFORM_LEVELS) {
        return CFG_MAX_LEVELS;
    }
    return ROM_U8(&limb_levels[limb]);
}

uint8_t psi_at_or_above(uint8_t limb, uint8_t thr, uint8_t edge, int16_t ax, int16_t az)
{
    return at_or_above(band(limb, thr)->e[edge == PSI_EDGE_LOWER], ax, az);
}

uint8_t psi_classify(uint8_t limb, uint8_t prev, int16_t ax, int16_t az)
{
    uint8_t top = (uint8_t)(psi_levels(limb) - 1u);
    uint8_t level = prev;
    if (level == PSI_UNKNOWN || level > top) {
        /* No history: count the thresholds whose upper edge ψ has reached. */
        level = 0;
    }
    while (level < top && psi_at_or_above(limb, level, PSI_EDGE_UPPER, ax, az)) {
        level++;
    }
    while (level > 0 && !psi_at_or_above(limb, (uint8_t)(level - 1u), PSI_EDGE_LOWER, ax, az)) {
        level--;
    }
    return level;
}

#if PSI_IN_LEVEL
/* The last sample of `limb` at or past ψ* of threshold `thr`: against the direction halfway
 * between the band's edges (the sum of their unit vectors, halved so it fits in 16 bits; only
 * its direction counts in at_or_above). */
static uint8_t last_past_star(uint8_t limb, uint8_t thr)
{
    const band_t *b = band(limb, thr);
    int16_t mid[2];
    mid[0] = (int16_t)((b->e[E_UPPER][0] >> 1) + (b->e[E_LOWER][0] >> 1));
    mid[1] = (int16_t)((b->e[E_UPPER][1] >> 1) + (b->e[E_LOWER][1] >> 1));
    return at_or_above(mid, limbs[limb].ax, limbs[limb].az);
}
#endif

/* The last sample of `limb` is inside its debounced level: clear of the band edges of
 * its thresholds (margins = 0) or of the hold and settle edges (margins = 1); with
 * PSI_RELAX_HELD_UP (margins = 2) the band above is not looked at. Settled in its level
 * (psi_settle_in_level), the edge below is ψ* itself, not the band's upper edge. */
static uint8_t inside(uint8_t limb, uint8_t margins)
{
    uint8_t level = limbs[limb].level;
    if (level == PSI_UNKNOWN) {
        return 0;
    }
#if PSI_IN_LEVEL
    if (level > 0u && limbs[limb].in_level && !(PSI_HELD_UP ? margins == 1u : margins)) {
        if (!last_past_star(limb, (uint8_t)(level - 1u))) {
            return 0; /* back below ψ*: its pad has switched back */
        }
    } else
#endif
    if (level > 0u && !last_above(limb, (uint8_t)(level - 1u), (PSI_HELD_UP ? margins == 1u : margins) ? E_HOLD : E_UPPER)) {
        return 0;
    }
    if (!(PSI_HELD_UP && margins == PSI_RELAX_HELD_UP) && level + 1u < psi_levels(limb) &&
        last_above(limb, level, margins ? E_SETTLE : E_LOWER)) {
        return 0;
    }
    return 1;
}

uint8_t psi_update(uint8_t limb, int16_t ax, int16_t az)
{
    limb_state_t *s = &limbs[limb];
    s->ax = ax;
    s->az = az;
#ifdef CFG_LIMB_STROKE_CDEG
    s->fresh = 0;
#endif
    /* arithmetic shifts (gcc and clang; ISO C leaves a negative's to the compiler): a division
     * rounds toward zero at twice the flash on the 8-bit targets */
    s->fx = (int16_t)(s->fx + (((ax >> 1) - s->fx) >> 4));
    s->fz = (int16_t)(s->fz + (((az >> 1) - s->fz) >> 4));
    s->hyst = psi_classify(limb, s->hyst, ax, az);
    if (s->level == PSI_UNKNOWN) {
        s->level = s->hyst;
        s->count = 0;
    } else if (s->hyst == s->level) {
        s->count = 0;
    } else {
        /* The hysteresis level can only move one way at a time between samples in
         * practice; any change restarts the count towards the new value. */
        s->count++;
        if (s->count >= debounce) {
            s->level = s->hyst;
            s->count = 0;
            s->settled = 0;
            s->dwell = 0;
#if PSI_IN_LEVEL
            s->in_level = 0; /* a new level: settled by its own edges again */
#endif
        }
    }
    /* dwell counts the samples that argue for a change: inside the margins while unsettled,
     * outside the band's edges while settled. A change needs `debounce` in a row, so one
     * noisy sample neither settles a limb nor unsettles it (a held end near the band's
     * edge, with IMU noise, kept the step from ever being reached and its coil heated). */
    /* relaxed: on the band edges (0), or held up (PSI_RELAX_HELD_UP, three or more limbs only) */
    if (s->settled ? !inside(limb, PSI_HELD_UP && s->relaxed == PSI_RELAX_HELD_UP ? PSI_RELAX_HELD_UP : 0)
                   : inside(limb, s->relaxed ? (PSI_HELD_UP ? s->relaxed & PSI_RELAX_HELD_UP : 0) : 1)) {
        if (++s->dwell >= debounce) {
            s->settled ^= 1u; /* settled, or left the band's edges: a real excursion */
            s->dwell = 0;
        }
    } else {
        s->dwell = 0;
    }
    return s->level;
}

void psi_relax(uint8_t limb, uint8_t on)
{
    limbs[limb].relaxed = on;
#if PSI_IN_LEVEL
    if (!on) {
        limbs[limb].in_level = 0; /* the limb's next target: the margins again */
    }
#endif
}

#if PSI_IN_LEVEL
void psi_settle_in_level(uint8_t limb)
{
    limb_state_t *l = &limbs[limb];
    if (l->level != PSI_UNKNOWN && l->level > 0u && psi_smooth_cdeg(limb) >= band(limb, (uint8_t)(l->level - 1u))->star) {
        l->in_level = 1; /* past ψ*: its pad has switched */
    }
}
#endif

uint8_t psi_level(uint8_t limb)
{
    return limbs[limb].level;
}

uint8_t psi_last_at_or_above_hold(uint8_t limb, uint8_t thr)
{
    return last_above(limb, thr, E_HOLD);
}

uint8_t psi_last_at_or_above_hold_top(uint8_t limb, uint8_t thr)
{
    return last_above(limb, thr, E_TOP);
}

int16_t psi_to_go_cdeg(uint8_t limb, uint8_t thr, uint8_t rising)
{
    const limb_state_t *l = &limbs[limb];
    const int16_t *e = band(limb, thr)->e[rising ? E_UPPER : E_LOWER];
    uint8_t k, n = rising ? PSI_PROGRESS_EDGES : PSI_FALL_EDGES;
    /* The sample in the frame of the band edge θ (upper when rising, lower when falling):
     * u = g·sin(ψ − θ), v = g·cos(ψ − θ). ψ ≥ θ ⇔ u ≥ 0 (exactly psi_at_or_above: u / 2^14
     * rounds down, so its sign is u's), and ψ ≥ θ − d ⇔ u·cos d + v·sin d ≥ 0, ψ ≥ θ + d ⇔
     * u·cos d − v·sin d ≥ 0. |g| < 2^15 (every sample imucheck.c passes is within 1.5 g)
     * keeps |u|, |v| below 2^29 for angle_turn_q14. */
    int16_t u16 = angle_turn_q14(e[0], e[1], l->ax, l->az);
    int16_t z16;
    if ((u16 >= 0) == !!rising) {
        return 0; /* rising: at or above the upper edge; falling: below the lower edge */
    }
    z16 = angle_turn_q14(e[1], (int16_t)-e[0], l->ax, l->az); /* v */
    if (rising) {
        z16 = (int16_t)-z16; /* the edges below the upper edge: turn the other way */
    }
    for (k = 0; k < n; k++) {
        const int16_t *p = progress[k];
        if ((angle_dot_q14(ROM_I16(&p[1]), ROM_I16(&p[2]), u16, z16) >= 0) == !!rising) {
            return ROM_I16(&p[0]);
        }
    }
    return PSI_FAR;
}

int16_t psi_smooth_cdeg(uint8_t limb)
{
    return angle_atan2_cdeg(limbs[limb].fx, limbs[limb].fz);
}

#define PSI_SIN_1DEG_Q16 1144 /* sin 1° × 65536 */

void psi_mark(uint8_t limb, psi_mark_t *m)
{
    m->x = limbs[limb].fx;
    m->z = limbs[limb].fz;
}

uint8_t psi_fell(uint8_t limb, psi_mark_t *m)
{
    const limb_state_t *l = &limbs[limb];
    /* ψ = atan2(x, z): |v||m| sin(ψ − ψm) = x·zm − z·xm; |m|² stands for |v||m| (halved samples:
     * |m|² < 2^28, the products and the difference fit an int32) */
    int32_t turn = (int32_t)l->fx * m->z - (int32_t)l->fz * m->x;
    int32_t norm = (int32_t)m->x * m->x + (int32_t)m->z * m->z;
    if (turn < -((norm >> 16) * PSI_SIN_1DEG_Q16)) {
        psi_mark(limb, m);
        return 1;
    }
    return 0;
}

uint8_t psi_settled(uint8_t limb)
{
    return limbs[limb].settled;
}

NOINLINE int16_t psi_last_centideg(uint8_t limb)
{
    limb_state_t *l = &limbs[limb];
    if (l->hyst == PSI_UNKNOWN) {
        return 0;
    }
#ifdef CFG_LIMB_STROKE_CDEG
    if (!l->fresh) {
        l->cdeg = angle_atan2_cdeg(l->ax, l->az);
        l->fresh = 1;
    }
    return l->cdeg;
#else
    return angle_atan2_cdeg(l->ax, l->az);
#endif
}
