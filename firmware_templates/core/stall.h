/* stall.h - ctl's watches on each limb's step: is it still getting anywhere (rules: ctl.h).
 *
 * Contract. ctl_demand calls stall_watch once per control tick for every limb whose level is
 * known: a new target starts the limb's step afresh (no verdict, psi_relax(i, 0)); then its
 * level changes and clocks give the stall detector's verdict (ctl_stall: oscillating, relaxed
 * by psi_relax; cannot reach), the climb clock of a limb rising to its stroke, the lag watch
 * and the held-up counts. stall_at_reach is the reach (and hold) watch of a limb whose coil
 * heats; stall_fall_watch says whether a fall is still coming down (DONE | DOWN | STUCK). The
 * watches look at the smoothed ψ once in CTL_REACH_EVERY ticks (ctl_look: the reach watch at 0,
 * the fall watch at FALL_LOOK), not every tick: the Nano's tick has no room for more atan2s.
 * The per-limb step state below is ctl.c's and this module's alone: ctl.c defines and clears
 * it (ctl_reset) and decides the duties with it; no other module includes this header.
 */
#ifndef PROLEG_STALL_H
#define PROLEG_STALL_H

#include <stdint.h>

#include "ctl.h"
#include "psi.h"
#include "robot_config.h"
#include "seq.h" /* SEQ_CLOCK_PAUSE */

#define TICKS(ms) ((uint16_t)(((uint32_t)(ms) * CFG_TICK_HZ + 999u) / 1000u))
#define NOT_SEEN 0xFFu
/* The reach watch runs in builds without full strokes (ctl.h, CTL_REACH_MS). With strokes, a
 * limb's climb is held back by the others' (CLIMBS_TO_STROKE): a rise cut as "cannot reach"
 * took that brake off, and R1 at full strokes with a dead right coil climbed its left end to a
 * stroke it could not reach, its coil at 173 °C instead of 107 °C. */
#ifdef CFG_LIMB_STROKE_CDEG
#define REACH_WATCH 0
#else
#define REACH_WATCH 1
#endif
/* The hold watch (ctl.h, CFG_HOLD_WATCH): in builds with the reach watch, where the robot's
 * body leaves a worn coil short of some limb's hold top. */
#define HOLD_WATCH (REACH_WATCH && CFG_HOLD_WATCH)
/* The knee watch (ctl.h, CTL_KNEE_MS). Stroke builds watch each limb the step raises to its
 * stroke while its own want heats its coil (ctl.c). Hold-watch builds watch the coil: every
 * limb whose coil is asked for the drive duty, whichever limb asks (KNEE_COIL, ctl.c): a coil
 * shared by several limbs (the one-actuator R1's, or a run-time map's) is heated for a limb it
 * lifts only through the body, while the end it bends itself shows its transformation. Other
 * builds (R1, R2, R3) carry no knee watch. */
#ifdef CFG_LIMB_STROKE_CDEG
#define KNEE_WATCH 1
#define KNEE_COIL 0
#else
#define KNEE_WATCH HOLD_WATCH
#define KNEE_COIL HOLD_WATCH
#endif
/* CTL_REACH_MS in looks of the reach watch, one every CTL_REACH_EVERY ticks (250 at 10 kHz) */
#define REACH_LOOKS ((TICKS(CTL_REACH_MS) + CTL_REACH_EVERY - 1u) / CTL_REACH_EVERY)

/* Per limb: the step it is in (target), and what the hold and the stall detector know. */
typedef struct {
    uint8_t target;    /* target level of the current step, PSI_UNKNOWN: none yet */
    uint8_t level;     /* debounced level at the previous call */
    uint8_t heat;      /* bang-bang hold: heating */
    uint8_t crossings; /* level changes in this step */
    int16_t best;      /* best psi_to_go_cdeg while rising in this step */
    uint8_t stall;     /* CTL_STALL_* */
    uint16_t ticks;    /* rising without progress / at the target level unsettled / falling: kept warm */
    uint8_t boost;     /* heats at the duty ceiling (once a rise lagged, until ctl_reset) */
    int16_t lo, hi;    /* reach watch: lowest smoothed ψ looked at in this step's rise, highest since */
    uint8_t still;     /* ... its looks since hi last rose; NOT_SEEN: none yet */
#if PSI_IN_LEVEL
    uint8_t risen;     /* rose CTL_MOVE_CDEG into its target level in this step, and has not settled
                        * there by the margins since, with its hold off (at its hold top): the hold
                        * watch's SAG_STOPPED, ctl.c */
#endif
#ifdef CFG_LIMB_STROKE_CDEG
    int16_t peak;      /* ψ (0.01°) when the hover clock last restarted on a climb */
    uint16_t clock;    /* ticks since this step began (saturating) */
    uint8_t climb;     /* this step raises it to its stroke (it began below its top level) */
    uint8_t shortfall; /* stopped climbing short of its stroke: held where it stopped until it leaves its top level */
    uint8_t lagged;    /* heated CTL_LAG_MS rising without progress in this step: not waited for (ctl.h) */
    uint8_t capping;   /* stopped short of its stroke in this robot step: the others in step climb no further */
#endif
#if KNEE_WATCH
    int16_t knee_at;   /* knee watch (ctl.h, CTL_KNEE_MS): smoothed ψ at the start of its window */
    int16_t fast;      /* ... the most it gained in one window of this heat at the drive duty */
    uint8_t knee_n;    /* ... looks into the window; 0: not heated at the drive duty (starts over) */
    uint8_t spent;     /* its coil went through its transformation in this step: no more than the hold duty */
#endif
#if CTL_HELD_UP
    uint16_t held_up;  /* ticks relaxed (oscillating) at its target level without settling, or
                        * falling without a CTL_CLIMB_CDEG drop of its smoothed ψ (ctl.h) */
#endif
#if SEQ_CLOCK_PAUSE
    psi_mark_t fall_low; /* lowest smoothed ψ of this step, in 1° drops (descent) */
    uint16_t fall_quiet; /* ticks since the last such drop */
#endif
} ctl_limb_t;

/* Defined in ctl.c. */
extern ctl_limb_t ctl_limb[CFG_N_LIMBS];
extern uint8_t ctl_look; /* ticks to the reach watch's next look, mod CTL_REACH_EVERY: it looks at 0 */
#ifdef CFG_LIMB_STROKE_CDEG
extern uint8_t ctl_waited; /* some limb climbing in step waited for another in the last tick (CLIMB_STOP) */
#endif

#ifdef CFG_LIMB_STROKE_CDEG
#define STROKE(i) (psi_stroke_cdeg(i) != PSI_NO_STROKE)
#define TOP(i, level) ((level) + 1u == psi_levels(i))
/* Limb i rises to its stroke in this step and is still at it (not relaxed, not cut off). */
#define CLIMBS_TO_STROKE(i, level) \
    (STROKE(i) && TOP(i, level) && ctl_limb[i].climb && ctl_limb[i].stall == CTL_STALL_NONE)
#endif

/* Stall detector of limb i for this tick (ctl.h), its level known: heating, it rises at the
 * drive duty or more; progress, its psi_to_go_cdeg (rising or falling, 0 when staying). */
void stall_watch(uint8_t i, uint8_t target, uint8_t level, uint8_t heating, int16_t progress);

/* Reach watch (ctl.h, CTL_REACH_MS) of limb i, its coil heating: 1 once its smoothed ψ rose
 * CTL_MOVE_CDEG from its lowest in this step and then gained less than CTL_GAIN_CDEG for
 * CTL_REACH_MS (c->still == REACH_LOOKS: it stopped). c->still = NOT_SEEN starts it over. */
uint8_t stall_at_reach(uint8_t i, ctl_limb_t *c);

#if KNEE_WATCH
/* Knee watch (ctl.h, CTL_KNEE_MS) of limb i (stroke builds: climbing to its stroke in this
 * step; KNEE_COIL: its coil asked for the drive duty by any limb); heated: its coil at the
 * drive duty this tick (not held off by the envelope). 1 once its coil is through its
 * transformation (c->spent); in a stroke build it also ends the climb of a limb on its top
 * level as stopped short of its stroke, as the hover clock does. */
uint8_t stall_knee(uint8_t i, uint8_t heated);
#endif

#if SEQ_CLOCK_PAUSE
/* The tick of CTL_REACH_EVERY in which the fall watch looks: not the reach watch's. */
#define FALL_LOOK (CTL_REACH_EVERY / 2u)
#define DONE 0u /* settled at its target level */
#define DOWN 1u /* coming down, a new low within CTL_FALL_PROGRESS_MS */
#define STUCK 2u
/* DONE | DOWN | STUCK of every limb: DOWN when some limb is coming down (ctl.h,
 * CTL_FALL_PROGRESS_MS) and none is stuck or rising. Call once in CTL_REACH_EVERY ticks. */
uint8_t stall_fall_watch(const uint8_t target[CFG_N_LIMBS]);
#endif

#endif /* PROLEG_STALL_H */
