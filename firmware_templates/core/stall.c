/* stall.c - see stall.h. */
#include "stall.h"

typedef char ctl_reach_fits_a_byte[REACH_LOOKS < NOT_SEEN ? 1 : -1];

#if SEQ_CLOCK_PAUSE
/* Limb i, its level known, in a fall still coming down (ctl.h, CTL_FALL_PROGRESS_MS), looked
 * at once every CTL_REACH_EVERY ticks (FALL_LOOK); stall_watch starts its lowest smoothed ψ afresh
 * at each new target, with no drop yet. */
static uint8_t descent(uint8_t i, uint8_t target, uint8_t level)
{
    ctl_limb_t *c = &ctl_limb[i];
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
uint8_t stall_fall_watch(const uint8_t target[CFG_N_LIMBS])
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
    return ctl_look == 0u && gained(i, c);
}

/* A limb climbing to its stroke on its top level has stopped after CTL_CLIMB_STOP_MS without a
 * gain, not a hover time (ctl.h); a hover time while another limb in step waits for it (its
 * wait takes the help of its coil away: R1 at full strokes at power 0.5 stopped at 36° of 76°). */
#define CLIMB_STOP(i, c, level) ((c)->climb && STROKE(i) && TOP(i, level) && !ctl_waited)
#else
#define climbing(i, c) 0
#define CLIMB_STOP(i, c, level) 0
#endif

#if KNEE_WATCH
/* Knee watch (ctl.h, CTL_KNEE_MS). Its own look in CTL_REACH_EVERY ticks (KNEE_LOOK), not the
 * climb's or the fall watch's: at most one more atan2 a limb in a tick. */
#define KNEE_LOOK (CTL_REACH_EVERY / 4u)
#define KNEE_LOOKS ((TICKS(CTL_KNEE_MS) + CTL_REACH_EVERY - 1u) / CTL_REACH_EVERY)
typedef char ctl_knee_fits_a_byte[KNEE_LOOKS < 255u ? 1 : -1];
/* c->fast through a heat's first window: the coil-wide knee does not count that window */
#if KNEE_COIL
#define KNEE_FIRST (-1)
#else
#define KNEE_FIRST 0
#endif

uint8_t stall_knee(uint8_t i, uint8_t heated)
{
    ctl_limb_t *c = &ctl_limb[i];
    int16_t m, g;
    if (!heated) {
        /* held at the hold duty, off, or cut by the envelope: its coil may cool below As, and
         * heated again it gains nothing through its dead time. Watched afresh: a knee needs a
         * fast window of the new heat first. */
        c->knee_n = 0;
        return c->spent;
    }
    if (c->spent || ctl_look != KNEE_LOOK) {
        return c->spent;
    }
    m = psi_smooth_cdeg(i);
    if (c->knee_n == 0u) {
        c->knee_at = m;
        c->fast = KNEE_FIRST;
        c->knee_n = 1;
        return 0;
    }
    if (++c->knee_n <= KNEE_LOOKS) {
        return 0;
    }
    g = (int16_t)(m - c->knee_at);
    c->knee_at = m;
    c->knee_n = 1;
#if KNEE_COIL
    if (c->fast < 0) {
        /* the first window of a heat is not the coil's (KNEE_FIRST): from below As it gains
         * nothing for its dead time, so what the smoothed ψ gained is the filter catching up
         * with a step of the reading. START levels the robot on the ground it rested on: on a
         * 5° decline the smoothed ψ glided 5° in the first 80 ms of the first rise from cold,
         * its dead time then read as the knee, and the coil was held at the hold duty for 5 s
         * (the one-actuator R1, claim bench decline: 2.31 -> 2.00 mm/s) */
        c->fast = 0;
    } else
#endif
    if (g > c->fast) {
        c->fast = g;
    } else if (c->fast >= CTL_KNEE_FAST_CDEG && g < (int16_t)(c->fast >> CTL_KNEE_SHIFT)) {
        c->spent = 1;
#ifdef CFG_LIMB_STROKE_CDEG
        if (c->climb && psi_level(i) == c->target) {
            /* on its top level: stopped short of its stroke, as the hover clock would say
             * (stall_watch), held where it stopped, and the others in step climb no further */
            c->stall = CTL_STALL_OSCILLATING;
            psi_relax(i, 1);
            c->shortfall = 1;
            c->capping = 1;
            c->peak = m;
            c->ticks = 0;
        }
        c->climb = 0; /* below its band: no longer the lead, nor waited for; held at the hold duty */
#endif
    }
    return c->spent;
}
#endif

/* Reach watch (ctl.h, CTL_REACH_MS) of limb i, rising alone with its coil heating: 1 once
 * its smoothed ψ rose CTL_MOVE_CDEG from its lowest in this step and then gained less than
 * CTL_GAIN_CDEG for CTL_REACH_MS. The rise counts from the lowest ψ: a limb may still sag
 * while its coil heats back to As. */
uint8_t stall_at_reach(uint8_t i, ctl_limb_t *c)
{
    int16_t m;
    if (ctl_look == 0u) {
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
            /* a held limb sagged from where it stopped: its re-heat is watched afresh, from where
             * it sagged to (kept at its old highest, a coil that cannot lift it back was heated
             * 20 looks in 21 for as long as the limb was held) */
            c->still = 0;
#if PSI_IN_LEVEL
            c->hi = m;
#endif
        }
#if PSI_IN_LEVEL
        if (c->hi - c->lo >= CTL_MOVE_CDEG) {
            c->risen = 1;
        }
#endif
    }
    return (uint8_t)(c->still == REACH_LOOKS && c->hi - c->lo >= CTL_MOVE_CDEG);
}

/* Stall detector of limb i for this tick (ctl.h). */
void stall_watch(uint8_t i, uint8_t target, uint8_t level, uint8_t heating, int16_t progress)
{
    ctl_limb_t *c = &ctl_limb[i];
    if (target != c->target) {
        c->target = target;
        c->crossings = 0;
        c->best = PSI_FAR;
        c->stall = CTL_STALL_NONE;
        c->ticks = 0;
        c->heat = 0;
        c->still = NOT_SEEN; /* the reach watch starts over */
#if PSI_IN_LEVEL
        c->risen = 0;
#endif
        psi_relax(i, 0);
#if CTL_HELD_UP
        c->held_up = 0;
#endif
#if SEQ_CLOCK_PAUSE
        psi_mark(i, &c->fall_low); /* the step's fall is measured from here, no drop yet */
        c->fall_quiet = TICKS(CTL_FALL_PROGRESS_MS);
#endif
#if KNEE_COIL
        {
            /* the robot's next step: every coil is watched afresh (the stroke builds' rule, ctl.c);
             * a coil heated in it starts from its dead time, a fast window of its own first */
            uint8_t j;
            for (j = 0; j < CFG_N_LIMBS; j++) {
                ctl_limb[j].spent = 0;
                ctl_limb[j].knee_n = 0;
            }
        }
#endif
    }
    if (level != c->level) {
        c->ticks = 0; /* a new level: the hover and stall clocks restart */
        if (c->level != PSI_UNKNOWN && c->crossings < CTL_OSC_CROSSINGS) {
            c->crossings++;
        }
        if (HOLD_WATCH && level < c->level) {
            c->still = NOT_SEEN; /* dropped from where the hold watch kept it: its rise back is watched afresh */
#if PSI_IN_LEVEL
            c->risen = 0;
#endif
#if KNEE_COIL
            c->spent = 0; /* its coil cooled back through its transformation: its rise back may heat it */
#endif
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
        if (c->shortfall && c->climb && ctl_look == 0u) {
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
    else if (level > target && ctl_look == 0u) {
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
