/* ctl.c - see ctl.h. */
#include "ctl.h"

#include <string.h>

#include "limbmap.h"
#include "psi.h"
#include "rom.h"
#include "sma.h"

/* What a limb asks of its actuator, weakest first; an actuator serves the strongest. */
enum { WANT_NOTHING, WANT_HOLD, WANT_RELEASE, WANT_HEAT, WANT_BOOST };
/* A limb's part in the current step. */
enum { STAY, RISE, FALL, SAG };

/* Held limbs sagging below their hold edge, for the falling limbs' wait: bit i+1 is limb i, so
 * a falling limb i looks at its neighbours i-1 and i+1 (bits i and i+2). With two limbs the
 * other one is the only neighbour: one flag, the same rule, no bytes spent on the Nano.
 * With three or more a held limb counts only once it has sagged to within CTL_SYNC_CDEG of
 * its band's lower edge (about to drop a level): its neighbours' coils tilt it by several
 * degrees at every step, far above its band, and a falling coil kept warm for that only
 * lengthened the step (ctl.h, docs/control.md "Long bodies"). */
#if CFG_N_LIMBS > 2
typedef uint16_t sag_t;
#define SAG_MARK(i) ((sag_t)(2u << (i)))
#define SAG_NEAR(s, i) (((s) >> (i)) & 5u)
#define SAG_COUNTS(i, thr) (psi_to_go_cdeg(i, thr, 0u) <= CTL_SYNC_CDEG)
#else
typedef uint8_t sag_t;
#define SAG_MARK(i) 1u
#define SAG_NEAR(s, i) (s)
#define SAG_COUNTS(i, thr) 1
#endif

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
/* CTL_REACH_MS in looks of the reach watch, one every CTL_REACH_EVERY ticks (250 at 10 kHz) */
#define REACH_LOOKS ((TICKS(CTL_REACH_MS) + CTL_REACH_EVERY - 1u) / CTL_REACH_EVERY)
typedef char ctl_reach_fits_a_byte[REACH_LOOKS < NOT_SEEN ? 1 : -1];
static uint8_t look; /* ticks to the reach watch's next look, mod CTL_REACH_EVERY: it looks at 0 */
#ifdef CFG_LIMB_STROKE_CDEG
static uint8_t waited; /* some limb climbing in step waited for another in the last tick (CLIMB_STOP) */
#endif

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
#ifdef CFG_LIMB_STROKE_CDEG
    int16_t peak;      /* ψ (0.01°) when the hover clock last restarted on a climb */
    uint16_t clock;    /* ticks since this step began (saturating) */
    uint8_t climb;     /* this step raises it to its stroke (it began below its top level) */
    uint8_t shortfall; /* stopped climbing short of its stroke: held where it stopped until it leaves its top level */
    uint8_t lagged;    /* heated CTL_LAG_MS rising without progress in this step: not waited for (ctl.h) */
    uint8_t capping;   /* stopped short of its stroke in this robot step: the others in step climb no further */
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
#if CTL_HELD_UP
static uint8_t hold_low; /* a falling limb is held up: held limbs hold just above their band (ctl.h) */
#endif
#if SEQ_CLOCK_PAUSE
static uint8_t coming_down; /* ctl_coming_down */
static uint8_t fall_down;   /* DONE | DOWN | STUCK of the limbs at the fall watch's last look */
#endif

static ctl_limb_t cl[CFG_N_LIMBS];
/* A variable, not the macro: comparing against a constant 0 would warn (-Wtype-limits). */
static const uint16_t boost_ticks = TICKS(CTL_BOOST_MS);

uint8_t ctl_limb_actuator(uint8_t limb)
{
    return limbmap_actuator(limb); /* run-time map (limbmap.h) */
}

void ctl_reset(void)
{
    uint8_t i;
    memset(cl, 0, sizeof cl); /* not heating, no crossings, no stall, no boost */
    look = 0;                 /* the reach watch's looks in the same phase after every reset */
#ifdef CFG_LIMB_STROKE_CDEG
    waited = 0;
#endif
#if CTL_HELD_UP
    hold_low = 0;
#endif
#if SEQ_CLOCK_PAUSE
    coming_down = 0;
    fall_down = 0; /* DONE: nothing coming down */
#endif
    for (i = 0; i < CFG_N_LIMBS; i++) {
        cl[i].target = PSI_UNKNOWN;
        cl[i].level = PSI_UNKNOWN;
        psi_relax(i, 0);
    }
}

uint8_t ctl_stall(uint8_t limb)
{
    return cl[limb].stall;
}

#if SEQ_CLOCK_PAUSE
uint8_t ctl_coming_down(void)
{
    return coming_down;
}

/* The tick of CTL_REACH_EVERY in which the fall watch looks: not the reach watch's. */
#define FALL_LOOK (CTL_REACH_EVERY / 2u)
#define DONE 0u /* settled at its target level */
#define DOWN 1u /* coming down, a new low within CTL_FALL_PROGRESS_MS */
#define STUCK 2u
/* Limb i, its level known, in a fall still coming down (ctl.h, CTL_FALL_PROGRESS_MS), looked
 * at once every CTL_REACH_EVERY ticks (FALL_LOOK); watch() starts its lowest smoothed ψ afresh
 * at each new target, with no drop yet. */
static uint8_t descent(uint8_t i, uint8_t target, uint8_t level)
{
    ctl_limb_t *c = &cl[i];
    if (level == target && psi_settled(i)) {
        return DONE;
    }
    if (level < target) {
        return STUCK; /* rising: its step's time runs */
    }
    if (psi_fell(i, &c->fall_low)) {
        c->fall_quiet = 0;
    } else if (c->fall_quiet < TICKS(CTL_FALL_PROGRESS_MS)) {
        c->fall_quiet = (uint16_t)(c->fall_quiet + CTL_REACH_EVERY);
    }
    return c->fall_quiet < TICKS(CTL_FALL_PROGRESS_MS) ? DOWN : STUCK;
}

/* DONE | DOWN | STUCK of every limb (descent). Out of line and once in CTL_REACH_EVERY ticks:
 * inlined in ctl_demand's loop, it cost R1 at full strokes on the Nano its tick's margin
 * (max 852 -> 1027 us of 1000, overruns) though it ran in no more than one tick of 16. */
#if defined(__GNUC__)
__attribute__((noinline))
#endif
static uint8_t fall_watch(const uint8_t target[CFG_N_LIMBS])
{
    uint8_t i, down = 0;
    for (i = 0; i < CFG_N_LIMBS; i++) {
        uint8_t level = psi_level(i);
        down |= level == PSI_UNKNOWN ? STUCK : descent(i, target[i], level);
    }
    return down;
}
#endif

#ifdef CFG_LIMB_STROKE_CDEG
#define STROKE(i) (psi_stroke_cdeg(i) != PSI_NO_STROKE)
#define TOP(i, level) ((level) + 1u == psi_levels(i))
/* Limb i rises to its stroke in this step and is still at it (not relaxed, not cut off). */
#define CLIMBS_TO_STROKE(i, level) (STROKE(i) && TOP(i, level) && cl[i].climb && cl[i].stall == CTL_STALL_NONE)
/* Limb i falls from its stroke: it has one and is still on its top level. */
#define FROM_STROKE(i, level) (STROKE(i) && TOP(i, level))
/* Limb i stopped climbing short of its stroke in its step, within CTL_CLIMB_MAX_MS of the step's start. */
#define STOPPED_SHORT(i, level) (STROKE(i) && TOP(i, level) && cl[i].capping && cl[i].clock < TICKS(CTL_CLIMB_MAX_MS))

/* Limb i's smoothed ψ rose CTL_CLIMB_GAIN_CDEG above c->peak: the peak moves up to it. */
static uint8_t gained(uint8_t i, ctl_limb_t *c)
{
    int16_t p = psi_smooth_cdeg(i);
    if (p >= c->peak + CTL_CLIMB_GAIN_CDEG) {
        c->peak = p; /* a new high: measure from here */
        return 1;
    }
    return 0;
}

/* A limb climbing to its stroke: its smoothed ψ gained (above) since the last time this said
 * so, within CTL_CLIMB_MAX_MS of the step's start. Its hover clock restarts, so it settles
 * at the stroke or where it stops climbing. Smoothed, because under IMU noise single samples
 * keep making new highs: a limb at the end of its reach counted as climbing, its coil at the
 * drive duty (R1 at full strokes, 1.5° of noise: 116 °C). Looked at with the reach watch's
 * pace (an atan2 each CTL_REACH_EVERY ticks, not each tick). */
static uint8_t climbing(uint8_t i, ctl_limb_t *c)
{
    if (!CLIMBS_TO_STROKE(i, psi_level(i)) || c->clock >= TICKS(CTL_CLIMB_MAX_MS)) {
        return 0;
    }
    if (c->ticks == 0u) {
        c->peak = psi_smooth_cdeg(i); /* a new level or a settled limb: measure from here */
        return 0;
    }
    return look == 0u && gained(i, c);
}

/* A limb climbing to its stroke on its top level has stopped after CTL_CLIMB_STOP_MS without a
 * gain, not a hover time (ctl.h); a hover time while another limb in step waits for it (its
 * wait takes the help of its coil away: R1 at full strokes at power 0.5 stopped at 36° of 76°). */
#define CLIMB_STOP(i, c, level) ((c)->climb && STROKE(i) && TOP(i, level) && !waited)

/* Limb i still rises: the others climbing in step wait for it (ctl.h, CTL_LAG_MS). */
#define STILL_RISING(i) (!cl[i].lagged)

/* How far limb i, climbing to its stroke on its top level, has got: 0 at its top band's upper
 * edge, CTL_SHARE_FULL at the stroke. */
static int16_t share(uint8_t i)
{
    int16_t lo = psi_upper_cdeg(i, (uint8_t)(psi_levels(i) - 2u));
    int16_t span = (int16_t)(psi_stroke_cdeg(i) - lo);
    int32_t got = (int32_t)(psi_last_centideg(i) - lo) * CTL_SHARE_FULL;
    if (span <= 0 || got <= 0) {
        return 0;
    }
    got /= span;
    return got > CTL_SHARE_FULL ? CTL_SHARE_FULL : (int16_t)got;
}

/* Held on threshold thr: at or above its hold edge (top = 0) or its hold top (1). A limb
 * that stopped short of its stroke is held where it stopped (ctl.h): its hold edge 1° below
 * where it stopped (peak), but never below the hold edge it has without a stroke. */
static uint8_t above_hold(uint8_t i, uint8_t thr, uint8_t level, uint8_t top)
{
    if (STROKE(i) && TOP(i, level) && cl[i].shortfall && !cl[i].climb) {
        int16_t edge = (int16_t)(cl[i].peak - CTL_CLIMB_CDEG);
        int16_t least_edge = (int16_t)(psi_upper_cdeg(i, thr) + CFG_HOLD_MARGIN_CDEG);
        if (edge < least_edge) {
            edge = least_edge;
        }
        return psi_last_centideg(i) >= edge + (top ? PSI_HOLD_BAND_CDEG : 0);
    }
    return top ? psi_last_at_or_above_hold_top(i, thr) : psi_last_at_or_above_hold(i, thr);
}
#define ABOVE_HOLD(i, thr, level) above_hold(i, thr, level, 0u)
#define ABOVE_TOP(i, thr, level) above_hold(i, thr, level, 1u)
#else
#define climbing(i, c) 0
#define CLIMB_STOP(i, c, level) 0
#define ABOVE_HOLD(i, thr, level) psi_last_at_or_above_hold(i, thr)
#define ABOVE_TOP(i, thr, level) psi_last_at_or_above_hold_top(i, thr)
#endif

/* Reach watch (ctl.h, CTL_REACH_MS) of limb i, rising alone with its coil heating: 1 once
 * its smoothed ψ rose CTL_MOVE_CDEG from its lowest in this step and then gained less than
 * CTL_GAIN_CDEG for CTL_REACH_MS. The rise counts from the lowest ψ: a limb may still sag
 * while its coil heats back to As. */
static uint8_t at_reach(uint8_t i, ctl_limb_t *c)
{
    int16_t m;
    if (look == 0u) {
        m = psi_smooth_cdeg(i);
        if (c->still == NOT_SEEN || m < c->lo) {
            c->lo = m;
            c->hi = m;
            c->still = 0;
        } else if (m >= c->hi + CTL_GAIN_CDEG) {
            c->hi = m;
            c->still = 0;
        } else if (c->still < REACH_LOOKS) {
            c->still++;
        } else if (HOLD_WATCH && m < c->hi - CTL_CLIMB_CDEG) {
            c->still = 0; /* a held limb sagged from where it stopped: its re-heat is watched afresh */
        }
    }
    return (uint8_t)(c->still == REACH_LOOKS && c->hi - c->lo >= CTL_MOVE_CDEG);
}

/* Stall detector of limb i for this tick (ctl.h). */
static void watch(uint8_t i, uint8_t target, uint8_t level, uint8_t heating, int16_t progress)
{
    ctl_limb_t *c = &cl[i];
    if (target != c->target) {
        c->target = target;
        c->crossings = 0;
        c->best = PSI_FAR;
        c->stall = CTL_STALL_NONE;
        c->ticks = 0;
        c->heat = 0;
        c->still = NOT_SEEN; /* the reach watch starts over */
        psi_relax(i, 0);
#if CTL_HELD_UP
        c->held_up = 0;
#endif
#if SEQ_CLOCK_PAUSE
        psi_mark(i, &c->fall_low); /* the step's fall is measured from here, no drop yet */
        c->fall_quiet = TICKS(CTL_FALL_PROGRESS_MS);
#endif
    }
    if (level != c->level) {
        c->ticks = 0; /* a new level: the hover and stall clocks restart */
        if (c->level != PSI_UNKNOWN && c->crossings < CTL_OSC_CROSSINGS) {
            c->crossings++;
        }
        if (HOLD_WATCH && level < c->level) {
            c->still = NOT_SEEN; /* dropped from where the hold watch kept it: its rise back is watched afresh */
        }
#if CTL_HELD_UP
        if (c->level > target || level > target) {
            c->held_up = 0; /* the fall watch's count (falling, or just down); at the target level
                             * the held-up settle's count runs on through its flips */
        }
#endif
        c->level = level;
    }
    if (c->stall != CTL_STALL_NONE) {
#ifdef CFG_LIMB_STROKE_CDEG
        /* Relaxed short of its stroke in the step that raises it (the crossings may have done
         * it mid-climb): heated on while its smoothed ψ still gains CTL_CLIMB_GAIN_CDEG a hover
         * time, then held where it stopped (above_hold). Heated on regardless, a worn coil at
         * the end of its stroke reached 134 °C, and with a dead neighbour 166 °C. */
        if (c->shortfall && c->climb && look == 0u) {
            if (gained(i, c)) {
                c->ticks = 0;
            } else if ((c->ticks = (uint16_t)(c->ticks + CTL_REACH_EVERY)) > TICKS(CTL_HOVER_MS)) {
                c->climb = 0; /* stopped: held where it stopped from now on */
                c->capping = 1;
            }
        }
#endif
#if CTL_HELD_UP
        /* relaxed and still not settled at its target level a hover time on: its neighbours
         * hold it up into the band above, its own coil off (ctl.h, CTL_HELD_UP) */
        if (c->stall == CTL_STALL_OSCILLATING && level == target && !psi_settled(i)) {
            if (c->held_up < TICKS(CTL_HOVER_MS)) {
                c->held_up++;
            } else {
                psi_relax(i, PSI_RELAX_HELD_UP);
            }
        }
#endif
        return; /* decided for this step */
    }
    if (level == target) {
        if (psi_settled(i)) {
            c->ticks = 0;
        } else if (climbing(i, c)) {
            c->ticks = 1;
        } else if (++c->ticks > TICKS(CLIMB_STOP(i, c, level) ? CTL_CLIMB_STOP_MS : CTL_HOVER_MS) ||
                   c->crossings >= CTL_OSC_CROSSINGS) {
            c->stall = CTL_STALL_OSCILLATING;
            psi_relax(i, 1);
#ifdef CFG_LIMB_STROKE_CDEG
            c->shortfall = (uint8_t)(c->climb && STROKE(i) && TOP(i, level));
            c->peak = psi_smooth_cdeg(i); /* where it stopped (climbing() may not have run); smoothed:
                                            * one noisy sample would set a hold it cannot reach */
            if (c->ticks > TICKS(CLIMB_STOP(i, c, level) ? CTL_CLIMB_STOP_MS : CTL_HOVER_MS)) {
                c->capping = c->shortfall;
                c->climb = 0; /* stopped climbing (not relaxed by crossings): held where it stopped */
            }
            c->ticks = 0; /* else the crossings relaxed it: the clock of its climb from here (above) */
#endif
        }
    } else if (heating) {
        if (progress < c->best) {
            c->best = progress;
            c->ticks = 0;
        } else if (++c->ticks >= TICKS(CTL_STALL_MS)) {
            c->stall = CTL_STALL_UNREACHABLE;
        }
#ifdef CFG_LIMB_STROKE_CDEG
        if (c->ticks >= TICKS(CTL_LAG_MS)) {
            c->lagged = 1; /* lags: not waited for in the rest of this step (ctl.h, CTL_LAG_MS) */
        }
#endif
    }
#if CTL_HELD_UP
    else if (level > target && look == 0u) {
        /* falling, within 2° of its crossing (psi_to_go_cdeg's fall edges; farther, its coil may
         * still be cooling to Ms): the lowest smoothed ψ of this step's fall there (the reach
         * watch's lo and still, unused while it falls); no drop of CTL_CLIMB_CDEG below it for
         * CTL_FALL_STALL_MS: held up (ctl.h) */
        if (progress == PSI_FAR) {
            c->still = NOT_SEEN;
            c->held_up = 0;
        } else {
            int16_t m = psi_smooth_cdeg(i);
            if (c->still == NOT_SEEN || m <= c->lo - CTL_CLIMB_CDEG) {
                c->lo = m;
                c->still = 0;
                c->held_up = 0;
            } else if (c->held_up < TICKS(CTL_FALL_STALL_MS)) {
                c->held_up = (uint16_t)(c->held_up + CTL_REACH_EVERY);
            }
        }
    }
#endif
}

void ctl_demand(const uint8_t target[CFG_N_LIMBS], uint16_t drive_pm, uint16_t hold_pm,
                uint16_t duty[CFG_N_ACTUATORS])
{
    uint8_t want[CFG_N_ACTUATORS];
    uint8_t move[CFG_N_LIMBS];
    int16_t to_go[CFG_N_LIMBS];
    uint8_t falling = 0, far_fall = 0;
#if CTL_HELD_UP
    uint8_t held_up = 0; /* some falling limb is held up (ctl.h, CTL_FALL_STALL_MS) */
#endif
    uint8_t changing = 0; /* limbs rising or falling */
    sag_t sagging = 0;
    int16_t farthest = -1;
    uint8_t i;
#ifdef CFG_LIMB_STROKE_CDEG
    int16_t got[CFG_N_LIMBS];
    int16_t least = CTL_SHARE_FULL;
    uint8_t lead_below = 0; /* the rise lead is rising to its stroke and has not crossed ψ* yet */
    uint8_t new_step = 0;   /* some limb's target changed: the robot's next step */
    int16_t stopped = CTL_SHARE_FULL; /* the least share of the limbs that stopped short of their strokes */
    uint8_t waiting = 0;              /* some limb climbing in step waits for another (waited, next tick) */
#endif
#ifdef CFG_STROKE_FALL_LEAD
    uint8_t lead_down = 0; /* the fall lead is falling from its stroke */
    uint8_t rising = 0;
#endif

    look = (uint8_t)((look + 1u) % CTL_REACH_EVERY);
#ifdef CFG_LIMB_STROKE_CDEG
    for (i = 0; i < CFG_N_LIMBS; i++) {
        new_step |= (uint8_t)(target[i] != cl[i].target && psi_level(i) != PSI_UNKNOWN);
    }
#endif
    for (i = 0; i < CFG_N_LIMBS; i++) {
        uint8_t level = psi_level(i);
        move[i] = STAY;
        to_go[i] = 0;
#ifdef CFG_LIMB_STROKE_CDEG
        got[i] = 0;
        if (target[i] != cl[i].target) { /* a new step for this limb */
            cl[i].clock = 0;
            cl[i].climb = (uint8_t)(level != PSI_UNKNOWN && level < target[i]);
            cl[i].lagged = 0;
            cl[i].capping = 0;
        } else if (new_step) {
            cl[i].climb = 0; /* the robot's next step, which leaves this limb where it is */
            cl[i].capping = 0;
        } else if (cl[i].clock != 0xFFFFu) {
            cl[i].clock++;
        }
        if (level == PSI_UNKNOWN || !TOP(i, level)) {
            cl[i].shortfall = 0;
        }
#endif
        if (level == PSI_UNKNOWN) {
            continue;
        }
        if (target[i] == level) {
            if (target[i] != cl[i].target) {
                cl[i].heat = 0;
            }
            if (level > 0u) {
                /* Bang-bang hold with hysteresis: heat from below the hold edge up to the
                 * hold top, then off until it sags below the hold edge again. */
                uint8_t thr = (uint8_t)(level - 1u);
#if CTL_HELD_UP
                if (hold_low) {
                    cl[i].heat = psi_to_go_cdeg(i, thr, 1u) > 0; /* below its band's upper edge (ctl.h) */
                } else
#endif
                if (!ABOVE_HOLD(i, thr, level)) {
                    cl[i].heat = 1;
                    if (SAG_COUNTS(i, thr)) {
                        sagging |= SAG_MARK(i);
                    }
                } else if (ABOVE_TOP(i, thr, level)) {
                    cl[i].heat = 0;
                }
                if (cl[i].heat) {
                    move[i] = SAG;
                }
#ifdef CFG_LIMB_STROKE_CDEG
                if (cl[i].heat && CLIMBS_TO_STROKE(i, level)) {
                    got[i] = share(i);
                    if (got[i] < least && STILL_RISING(i)) {
                        least = got[i];
                    }
                } else if (STOPPED_SHORT(i, level) && share(i) < stopped) {
                    stopped = share(i);
                }
#endif
            }
            continue;
        }
        move[i] = target[i] > level ? RISE : FALL;
#ifdef CFG_LIMB_STROKE_CDEG
        if (move[i] == RISE && CLIMBS_TO_STROKE(i, target[i])) {
            if (STILL_RISING(i)) {
                least = 0; /* not past its band yet: nothing of its climb to the stroke covered */
            }
            lead_below |= (uint8_t)(i == CFG_STROKE_RISE_LEAD);
        }
#endif
#ifdef CFG_STROKE_FALL_LEAD
        rising |= (uint8_t)(move[i] == RISE);
        lead_down |= (uint8_t)(i == CFG_STROKE_FALL_LEAD && move[i] == FALL && FROM_STROKE(i, level) &&
                               share(i) > CTL_FALL_SHARE);
#endif
        to_go[i] = psi_to_go_cdeg(i, move[i] == RISE ? level : (uint8_t)(level - 1u), (uint8_t)(move[i] == RISE));
        changing++;
        if (to_go[i] > farthest) {
            farthest = to_go[i];
        }
        if (move[i] == FALL) {
            falling = 1;
            if (to_go[i] > CTL_SYNC_CDEG) {
                far_fall = 1; /* some falling limb is not about to cross yet */
            }
        }
    }

    for (i = 0; i < CFG_N_ACTUATORS; i++) {
        want[i] = WANT_NOTHING;
    }
    for (i = 0; i < CFG_N_LIMBS; i++) {
        uint8_t level = psi_level(i);
        uint8_t w, a;
        if (move[i] == RISE) {
            /* Rising with others (ctl.h): wait at the hold duty while more than
             * CTL_SYNC_CDEG ahead of the farthest (never true when rising alone), or, if some limb
             * falls, in the zone below the crossing until every falling limb is about
             * to cross. */
            uint8_t wait = falling ? to_go[i] <= CTL_SYNC_ZONE_CDEG && far_fall
                                   : to_go[i] < farthest - CTL_SYNC_CDEG; /* −201 ≤ farthest − 200: no overflow */
            if (boost_ticks != 0u && cl[i].target == target[i] && cl[i].ticks >= boost_ticks) {
                cl[i].boost = 1;
            }
#ifdef CFG_LIMB_STROKE_CDEG
            if (CLIMBS_TO_STROKE(i, target[i]) && !falling) {
                /* all rising: instead of crossing together, the rise lead crosses first and
                 * the others wait, warm for at most CTL_SAG_WAIT_MS (ctl.h) */
                wait = lead_below && i != CFG_STROKE_RISE_LEAD;
                if (wait && cl[i].clock >= TICKS(CTL_SAG_WAIT_MS)) {
                    wait = 2u; /* waited long enough warm: off until it has crossed */
                }
            }
            w = wait == 1u ? WANT_HOLD : wait ? WANT_RELEASE : WANT_HEAT + cl[i].boost;
#else
            w = wait ? WANT_HOLD : WANT_HEAT + cl[i].boost;
#endif
        } else if (move[i] == FALL) {
            /* It may be what holds a sagging neighbour (limb i-1 or i+1: the coils that
             * bend the same body section) up: kept warm while one sags, for at most
             * CTL_SAG_WAIT_MS in this step (with several limbs held one of them nearly always
             * sags, and a falling coil kept warm for good would never cross). A limb further
             * away does not wait: its coil barely moves that end. */
            w = WANT_RELEASE;
            if (SAG_NEAR(sagging, i) != 0u && cl[i].ticks < TICKS(CTL_SAG_WAIT_MS)) {
                cl[i].ticks++;
                w = WANT_HOLD;
            }
#ifdef CFG_STROKE_FALL_LEAD
            if (!rising && lead_down && i != CFG_STROKE_FALL_LEAD && FROM_STROKE(i, level) &&
                cl[i].clock < TICKS(CTL_FALL_WAIT_MS)) {
                /* all falling from strokes: held at its stroke until the fall lead is down (ctl.h) */
                w = ABOVE_HOLD(i, (uint8_t)(level - 1u), level) ? WANT_NOTHING : WANT_HEAT;
            }
#endif
        } else if (move[i] == SAG) {
            w = WANT_HEAT + cl[i].boost;
#ifdef CFG_LIMB_STROKE_CDEG
            if (CLIMBS_TO_STROKE(i, level) && got[i] > least + CTL_SHARE_SYNC &&
                cl[i].clock < TICKS(CTL_CLIMB_MAX_MS)) {
                w = WANT_HOLD;     /* ahead of another limb's climb: wait for it (ctl.h) */
                cl[i].ticks = 0u;  /* not hovering: waiting */
                waiting = 1;
            } else if (CLIMBS_TO_STROKE(i, level) && got[i] > stopped + CTL_SHARE_SYNC &&
                       cl[i].ticks > TICKS(CTL_CLIMB_STOP_MS / 2u)) {
                w = WANT_HOLD; /* past where a limb in step stopped short and no longer gaining: hovers (ctl.h) */
            }
#endif
        } else if (level == PSI_UNKNOWN) {
            w = WANT_NOTHING;
        } else if (!psi_settled(i)) {
            w = WANT_RELEASE; /* not yet settled clear of the level above */
        } else {
            w = WANT_NOTHING; /* held level between hold edge and top: coil off (bang-bang) */
        }
        if (level != PSI_UNKNOWN) {
            watch(i, target[i], level, (uint8_t)(w >= WANT_HEAT && move[i] == RISE), to_go[i]);
            /* Its coil heating and not held off by the envelope, its ψ stopped answering (ctl.h):
             * - rising alone (the body couples limbs that move together), short of its level:
             *   it cannot get there, as after CTL_STALL_MS without progress but at once;
             * - with the hold watch, held and relaxed (it never settled clear of its hold edge),
             *   settled clear of its band (the step needs no more of it) and heating below that
             *   edge: held where it stopped, its coil off until it sags CTL_CLIMB_CDEG below its
             *   highest. */
            if (REACH_WATCH && w >= WANT_HEAT &&
                (move[i] == RISE ? changing == 1u
                                 : HOLD_WATCH && move[i] == SAG && cl[i].stall == CTL_STALL_OSCILLATING &&
                                       psi_settled(i))) {
                if (sma_cooling(ctl_limb_actuator(i))) {
                    cl[i].still = NOT_SEEN; /* held off: it starts over, from a cooler coil */
                } else if (at_reach(i, &cl[i]) && move[i] == RISE) {
                    cl[i].stall = CTL_STALL_UNREACHABLE;
                } else if (cl[i].still == REACH_LOOKS && move[i] == SAG) {
                    w = WANT_NOTHING;
                }
            }
            if (cl[i].stall == CTL_STALL_UNREACHABLE && move[i] == RISE) {
                w = WANT_NOTHING; /* cannot get there: stop heating, let it cool */
            }
#if CTL_HELD_UP
            held_up |= (uint8_t)(move[i] == FALL && cl[i].held_up >= TICKS(CTL_FALL_STALL_MS));
#endif
        }
        a = ctl_limb_actuator(i);
        if (w > want[a]) {
            want[a] = w;
        }
    }
    /* Without CTL_BOOST_MS no limb is ever boosted (boost stays 0: WANT_HEAT is the strongest
     * want), so the ceiling's case is compiled out and heat is "at least WANT_HEAT": the same
     * duties, R1 24 B smaller on the Nano. */
#if CTL_HELD_UP
    hold_low = held_up; /* the holds of the next tick */
#endif
#ifdef CFG_LIMB_STROKE_CDEG
    waited = waiting;
#endif
#if SEQ_CLOCK_PAUSE
    if (look == FALL_LOOK) {
        fall_down = fall_watch(target);
    }
    coming_down = (uint8_t)(fall_down == DOWN); /* some limb coming down, none stuck or rising */
    for (i = 0; i < CFG_N_ACTUATORS; i++) {
        if (want[i] >= WANT_HEAT) {
            coming_down = 0; /* a coil asked for more than the hold: its step's time runs */
        }
    }
#endif
    for (i = 0; i < CFG_N_ACTUATORS; i++) {
        duty[i] = (CTL_BOOST_MS && want[i] == WANT_BOOST) ? (uint16_t)CFG_MAX_DUTY_PM : want[i] >= WANT_HEAT ? drive_pm : want[i] == WANT_HOLD ? hold_pm : 0u;
    }
}
