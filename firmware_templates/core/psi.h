/* psi.h - contact angle ψ: level classifier (control path) and estimate (telemetry).
 *
 * Contract. Each limb i has levels k_i and k_i-1 critical angles ψ*_j, each with a
 * hysteresis band [ψ*_j - h/2, ψ*_j + h/2]. robot_config.h gives, per limb and
 * threshold, the cos and sin of both band edges in Q14 (computed at render time).
 * ψ ≥ θ  ⇔  ax·cos θ − az·sin θ ≥ 0  for ψ, θ in (−90°, 90°), because the accelerometer
 * reads g·(sin ψ, ·, cos ψ). So the control path needs no atan2 and no floats.
 *
 * Level with hysteresis: from level L a limb goes up past threshold L when ψ ≥ its
 * upper edge, down past threshold L−1 when ψ < its lower edge. Debounce: the reported
 * level changes only after the hysteresis level has held the new value for `debounce`
 * consecutive samples. psi_last_centideg() is an integer atan2 (angle.h, error < 0.01°) for
 * telemetry only: everything the controller asks (levels, hold and settle edges, progress
 * towards a crossing) is a comparison against Q14 edge constants (angle.h's sin and cos)
 * computed when a band is set.
 *
 * Settled, with hysteresis and dwell: a limb becomes settled once its last sample has been
 * inside its debounced level clear of the margins (at or above the hold edge below it,
 * below the settle edge above it) for `debounce` consecutive samples, and stays settled
 * until it has been outside the band edges themselves (below ψ*+h/2 of the threshold under
 * it, at or above ψ*−h/2 of the one above) for `debounce` consecutive samples, or its level
 * changes. Relaxed (psi_relax, set by the
 * controller when a limb oscillates at a threshold), the margins are not required.
 */
#ifndef PROLEG_PSI_H
#define PROLEG_PSI_H

#include <stdint.h>

#include "robot_config.h"

#define PSI_EDGE_UPPER 0u
#define PSI_EDGE_LOWER 1u
#define PSI_UNKNOWN 0xFFu

/* Progress edges towards a crossing (psi_to_go_cdeg): distances from the band edge in
 * 0.01°, fine near the crossing, coarse far from it; falling limbs use the first
 * PSI_FALL_EDGES only. */
#define PSI_PROGRESS_EDGES 13
#define PSI_PROGRESS_CDEG {100, 200, 300, 400, 500, 600, 800, 1000, 1200, 1500, 2000, 2500, 3000}
#define PSI_FALL_EDGES 2
#define PSI_FAR 0x7FFF
/* Width of the hold band above the hold edge (bang-bang hold, ctl.h), 0.01°. */
#define PSI_HOLD_BAND_CDEG 100

/* Load the rendered thresholds and forget all history. */
void psi_init(void);

/* Forget all history: the next sample of each limb sets its level directly. */
void psi_reset(void);

/* Samples the reported level must be stable for (1 = no debounce). */
void psi_set_debounce(uint16_t samples);

/* Move threshold `thr` of `limb` to ψ* ± h/2 (0.01°) at run time (SET_PARAM); the Q14
 * constants are recomputed with an integer sine table. Returns 0, or -1 (nothing changed)
 * when the band leaves (−90°, 90°) or overlaps a neighbouring threshold's band. */
int8_t psi_set_band(uint8_t limb, uint8_t thr, int16_t psi_star_cdeg, int16_t hyst_cdeg);

/* Give every threshold of `limb` the band width h (0.01°), keeping their ψ*: all of them or,
 * returning -1, none (h outside 0..2000, a band leaving (−90°, 90°), or two bands meeting). */
int8_t psi_set_hysteresis(uint8_t limb, int16_t hyst_cdeg);

/* ψ* and band width in use for threshold `thr` of `limb`, 0.01°. */
int16_t psi_star_cdeg(uint8_t limb, uint8_t thr);
int16_t psi_hyst_cdeg(uint8_t limb, uint8_t thr);

/* 1 when the gravity vector (ax, az) of `limb` is at or above the `edge` of threshold `thr`. */
uint8_t psi_at_or_above(uint8_t limb, uint8_t thr, uint8_t edge, int16_t ax, int16_t az);

/* Hysteresis level of (ax, az) given the previous hysteresis level (PSI_UNKNOWN: none). */
uint8_t psi_classify(uint8_t limb, uint8_t prev, int16_t ax, int16_t az);

/* Feed one accelerometer sample of `limb`; returns its debounced level. */
uint8_t psi_update(uint8_t limb, int16_t ax, int16_t az);

/* Debounced level of `limb` (PSI_UNKNOWN before its first sample). */
uint8_t psi_level(uint8_t limb);

/* 1 when the last sample of `limb` is at or above the hold edge of threshold `thr`:
 * the upper edge plus CFG_HOLD_MARGIN_CDEG, where the controller holds a raised level;
 * for the top threshold of a limb with a stroke (CFG_LIMB_STROKE_CDEG, robot file
 * [[limb]] stroke_deg) the stroke itself, so the limb settles on its top level only once
 * it got there (or once it stopped climbing: ctl.h). */
uint8_t psi_last_at_or_above_hold(uint8_t limb, uint8_t thr);

/* A limb without a stroke in CFG_LIMB_STROKE_CDEG. */
#define PSI_NO_STROKE (-32767 - 1)

#ifdef CFG_LIMB_STROKE_CDEG
/* The upper edge ψ* + h/2 of threshold `thr`'s band in use, 0.01°. */
int16_t psi_upper_cdeg(uint8_t limb, uint8_t thr);

/* The stroke of `limb` in 0.01°, or PSI_NO_STROKE: it has none, or its top ψ* was moved
 * (SET_PARAM) up to it or past it. */
int16_t psi_stroke_cdeg(uint8_t limb);
#endif

/* 1 when the last sample of `limb` is at or above the hold top of threshold `thr`: the
 * hold edge plus PSI_HOLD_BAND_CDEG. */
uint8_t psi_last_at_or_above_hold_top(uint8_t limb, uint8_t thr);

/* How far the last sample of `limb` still is from crossing threshold `thr` (to the
 * band's upper edge when `rising`, to its lower edge when falling), rounded up to the
 * next of PSI_PROGRESS_CDEG: 0 once past, PSI_FAR beyond the last edge (rising 30°,
 * falling 2°). Comparisons against Q14 edges only, no atan. */
int16_t psi_to_go_cdeg(uint8_t limb, uint8_t thr, uint8_t rising);

/* ψ of `limb` smoothed in 0.01°: the angle of its samples' exponential mean (1/16 of each new
 * one: about a fifth of a sample's noise, a lag of about 16 samples), for the controller's
 * watch on a rise that stops short (ctl.h, CTL_REACH_MS). One atan2 a call. */
int16_t psi_smooth_cdeg(uint8_t limb);

/* A direction of `limb`'s smoothed samples (those of psi_smooth_cdeg), kept to compare with:
 * psi_mark puts it at the limb's direction now; psi_fell is 1, and moves it there, once the
 * smoothed ψ is 1° or more below it (a cross product, no atan: the fall watch of ctl.h,
 * CTL_FALL_PROGRESS_MS, looks at falling limbs in ticks that an atan2 a limb overran on the
 * Nano). The samples' magnitude is taken as the mark's (at rest it is g, whatever ψ). */
typedef struct {
    int16_t x, z;
} psi_mark_t;
void psi_mark(uint8_t limb, psi_mark_t *m);
uint8_t psi_fell(uint8_t limb, psi_mark_t *m);

/* 1 when `limb` is settled in its debounced level (see above). */
uint8_t psi_settled(uint8_t limb);

/* Settle on the band edges alone (on = PSI_RELAX_EDGES) or with the margins (0, the default);
 * PSI_RELAX_HELD_UP: on the band edge below alone, whatever the band above says (a limb its
 * neighbours hold up into the band above its level, its own coil off: ctl.h). */
#define PSI_RELAX_EDGES 1u
#define PSI_RELAX_HELD_UP 2u
/* Built for three or more limbs only (ctl.h, CTL_HELD_UP): R1's image has no bytes to spare. */
#define PSI_HELD_UP (CFG_N_LIMBS > 2)
void psi_relax(uint8_t limb, uint8_t on);

/* Settle in the debounced level itself, if the limb's smoothed ψ is at or past the ψ* below
 * its level (its pad has switched): on that ψ* instead of the band's upper edge, so that it
 * stays settled as long as its pad is switched, until psi_relax(limb, 0) at the limb's next
 * target or a change of its level. Short of ψ* nothing changes. For a limb whose coil has given all it has inside
 * its band (ctl.h, the hold watch): its level is reached as far as this coil can reach it.
 * Built with the hold watch only (CFG_HOLD_WATCH; not with strokes, which run no reach watch):
 * R1's image has no bytes to spare. */
#if CFG_HOLD_WATCH && !defined(CFG_LIMB_STROKE_CDEG)
#define PSI_IN_LEVEL 1
void psi_settle_in_level(uint8_t limb);
#else
#define PSI_IN_LEVEL 0
#endif

/* Every limb has CFG_MAX_LEVELS levels exactly when their product, CFG_N_STATES, is
 * CFG_MAX_LEVELS^CFG_N_LIMBS (no limb has more): then psi_levels() is a constant the compiler
 * folds into every caller (R1, R3, inchworm-3). Up to 8 limbs; more read the table. Usable
 * in #if. */
#define PSI_POW_(k) (CFG_N_LIMBS > (k) ? CFG_MAX_LEVELS : 1UL)
#define PSI_UNIFORM_LEVELS                                                                                  \
    (CFG_N_LIMBS <= 8u && CFG_N_STATES == PSI_POW_(0) * PSI_POW_(1) * PSI_POW_(2) * PSI_POW_(3) * PSI_POW_(4) * \
                              PSI_POW_(5) * PSI_POW_(6) * PSI_POW_(7))

/* Number of levels of `limb`. */
uint8_t psi_levels(uint8_t limb);

/* ψ of the last sample of `limb` in 0.01° (0 before its first sample). */
int16_t psi_last_centideg(uint8_t limb);

#endif /* PROLEG_PSI_H */
