/* ctl.c - see ctl.h. The watches on each limb's step (stall detector, reach, hold, fall) are
 * stall.c's; this file turns the levels, the targets and their verdicts into duties. */
#include "ctl.h"

#include <string.h>

#include "limbmap.h"
#include "psi.h"
#include "rom.h"
#include "sma.h"
#include "stall.h"

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

/* The hold watch's cut of a limb at its level (below, ctl_demand): settled (clear of its band,
 * relaxed), or not settled and risen CTL_MOVE_CDEG into its level in this step before it stopped
 * gaining (ctl_limb_t risen; settled by the margins without getting to its hold top, it is still
 * risen). A held limb that settled by the margins and then sags back into its band has not risen
 * so since: its coil may be in its dead time (0.15-0.6 s back to As), and it is heated on as
 * before. */
#if PSI_IN_LEVEL
#define SAG_STOPPED(i) (psi_settled(i) || ctl_limb[i].risen)
#define RISEN(i) ctl_limb[i].risen
#else
#define SAG_STOPPED(i) 1
#define RISEN(i) 0
#endif

/* A limb whose own coil the fallback gave up is at its level only as far as the body lifts it
 * (fallback.h): it is never heated toward its hold edge (below, ctl_demand). The coil it is
 * mapped to holds its own limb; heated on for this one past the end of that limb's travel it
 * only cooked (R2 with a mismatched pair: 128-130 °C every cycle). */
#if !CFG_FALLBACK
#define GIVEN_UP(i) 0
#elif CFG_LIMB_ACTUATOR_IS_INDEX
#define GIVEN_UP(i) ((i) == limbmap_lost()) /* its own actuator is actuator i: R1 16 B, not 36 */
#else
#define GIVEN_UP(i) limbmap_given_up(i)
#endif

/* Shared with the watches (stall.h). */
ctl_limb_t ctl_limb[CFG_N_LIMBS];
uint8_t ctl_look;
#ifdef CFG_LIMB_STROKE_CDEG
uint8_t ctl_waited;
#endif
#if CTL_HELD_UP
static uint8_t hold_low; /* a falling limb is held up: held limbs hold just above their band (ctl.h) */
#endif
#if SEQ_CLOCK_PAUSE
static uint8_t coming_down; /* ctl_coming_down */
static uint8_t fall_down;   /* DONE | DOWN | STUCK of the limbs at the fall watch's last look */
#endif

/* A variable, not the macro: comparing against a constant 0 would warn (-Wtype-limits). */
static const uint16_t boost_ticks = TICKS(CTL_BOOST_MS);

uint8_t ctl_limb_actuator(uint8_t limb)
{
    return limbmap_actuator(limb); /* run-time map (limbmap.h) */
}

void ctl_reset(void)
{
    uint8_t i;
    memset(ctl_limb, 0, sizeof ctl_limb); /* not heating, no crossings, no stall, no boost */
    ctl_look = 0;                         /* the reach watch's looks in the same phase after every reset */
#ifdef CFG_LIMB_STROKE_CDEG
    ctl_waited = 0;
#endif
#if CTL_HELD_UP
    hold_low = 0;
#endif
#if SEQ_CLOCK_PAUSE
    coming_down = 0;
    fall_down = 0; /* DONE: nothing coming down */
#endif
    for (i = 0; i < CFG_N_LIMBS; i++) {
        ctl_limb[i].target = PSI_UNKNOWN;
        ctl_limb[i].level = PSI_UNKNOWN;
        psi_relax(i, 0);
    }
}

uint8_t ctl_stall(uint8_t limb)
{
    return ctl_limb[limb].stall;
}

#if SEQ_CLOCK_PAUSE
uint8_t ctl_coming_down(void)
{
    return coming_down;
}
#endif

#ifdef CFG_LIMB_STROKE_CDEG
/* Limb i falls from its stroke: it has one and is still on its top level. */
#define FROM_STROKE(i, level) (STROKE(i) && TOP(i, level))
/* Limb i stopped climbing short of its stroke in its step, within CTL_CLIMB_MAX_MS of the step's start. */
#define STOPPED_SHORT(i, level) (STROKE(i) && TOP(i, level) && ctl_limb[i].capping && ctl_limb[i].clock < TICKS(CTL_CLIMB_MAX_MS))

/* Limb i still rises: the others climbing in step wait for it (ctl.h, CTL_LAG_MS). */
#define STILL_RISING(i) (!ctl_limb[i].lagged)

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
    if (STROKE(i) && TOP(i, level) && ctl_limb[i].shortfall && !ctl_limb[i].climb) {
        int16_t edge = (int16_t)(ctl_limb[i].peak - CTL_CLIMB_CDEG);
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
#define ABOVE_HOLD(i, thr, level) psi_last_at_or_above_hold(i, thr)
#define ABOVE_TOP(i, thr, level) psi_last_at_or_above_hold_top(i, thr)
#endif

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
    uint8_t waiting = 0;              /* some limb climbing in step waits for another (ctl_waited, next tick) */
#endif
#ifdef CFG_STROKE_FALL_LEAD
    uint8_t lead_down = 0; /* the fall lead is falling from its stroke */
    uint8_t rising = 0;
#endif

    ctl_look = (uint8_t)((ctl_look + 1u) % CTL_REACH_EVERY);
#ifdef CFG_LIMB_STROKE_CDEG
    for (i = 0; i < CFG_N_LIMBS; i++) {
        new_step |= (uint8_t)(target[i] != ctl_limb[i].target && psi_level(i) != PSI_UNKNOWN);
    }
#endif
    for (i = 0; i < CFG_N_LIMBS; i++) {
        uint8_t level = psi_level(i);
        move[i] = STAY;
        to_go[i] = 0;
#ifdef CFG_LIMB_STROKE_CDEG
        got[i] = 0;
        if (target[i] != ctl_limb[i].target) { /* a new step for this limb */
            ctl_limb[i].clock = 0;
            ctl_limb[i].climb = (uint8_t)(level != PSI_UNKNOWN && level < target[i]);
            ctl_limb[i].lagged = 0;
            ctl_limb[i].capping = 0;
            ctl_limb[i].spent = 0;
            ctl_limb[i].knee_n = 0;
        } else if (new_step) {
            ctl_limb[i].climb = 0; /* the robot's next step, which leaves this limb where it is */
            ctl_limb[i].capping = 0;
            ctl_limb[i].spent = 0; /* its coil has had the steps' change to cool: its hold may re-heat it */
        } else if (ctl_limb[i].clock != 0xFFFFu) {
            ctl_limb[i].clock++;
        }
        if (level == PSI_UNKNOWN || !TOP(i, level)) {
            ctl_limb[i].shortfall = 0;
        }
#endif
        if (level == PSI_UNKNOWN) {
            continue;
        }
        if (target[i] == level) {
            if (target[i] != ctl_limb[i].target) {
                ctl_limb[i].heat = 0;
            }
#if PSI_IN_LEVEL
            /* held by the margins: a sag from here is a re-heat (SAG_STOPPED). Held once the
             * bang-bang hold is off, i.e. the limb got to its hold top since it last heated: a rise
             * that settles by the margins short of its hold edge and creeps on below it, its coil
             * at the drive duty, is still watched (risen). snake-8's tail, worn by 22,868 cycles,
             * settled at 24.95° against its 25° hold edge and was heated 3 s on to 140 °C. */
            if (psi_settled(i) && ctl_limb[i].stall == CTL_STALL_NONE && !ctl_limb[i].heat) {
                ctl_limb[i].risen = 0;
                ctl_limb[i].still = NOT_SEEN;
            }
#endif
            if (level > 0u) {
                /* Bang-bang hold with hysteresis: heat from below the hold edge up to the
                 * hold top, then off until it sags below the hold edge again. */
                uint8_t thr = (uint8_t)(level - 1u);
#if CTL_HELD_UP
                if (hold_low) {
                    ctl_limb[i].heat = psi_to_go_cdeg(i, thr, 1u) > 0; /* below its band's upper edge (ctl.h) */
                } else
#endif
                if (!ABOVE_HOLD(i, thr, level)) {
                    ctl_limb[i].heat = 1;
                    if (SAG_COUNTS(i, thr)) {
                        sagging |= SAG_MARK(i);
                    }
                } else if (ABOVE_TOP(i, thr, level)) {
                    ctl_limb[i].heat = 0;
                }
                if (GIVEN_UP(i)) {
                    ctl_limb[i].heat = 0; /* nor does it count as climbing (the strokes' bookkeeping) */
                }
                if (ctl_limb[i].heat) {
                    move[i] = SAG;
                }
#ifdef CFG_LIMB_STROKE_CDEG
                if (ctl_limb[i].heat && CLIMBS_TO_STROKE(i, level)) {
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
            if (boost_ticks != 0u && ctl_limb[i].target == target[i] && ctl_limb[i].ticks >= boost_ticks) {
                ctl_limb[i].boost = 1;
            }
#ifdef CFG_LIMB_STROKE_CDEG
            if (CLIMBS_TO_STROKE(i, target[i]) && !falling) {
                /* all rising: instead of crossing together, the rise lead crosses first and
                 * the others wait, warm for at most CTL_SAG_WAIT_MS (ctl.h) */
                wait = lead_below && i != CFG_STROKE_RISE_LEAD;
                if (wait && ctl_limb[i].clock >= TICKS(CTL_SAG_WAIT_MS)) {
                    wait = 2u; /* waited long enough warm: off until it has crossed */
                }
            }
            w = wait == 1u ? WANT_HOLD : wait ? WANT_RELEASE : WANT_HEAT + ctl_limb[i].boost;
#else
            w = wait ? WANT_HOLD : WANT_HEAT + ctl_limb[i].boost;
#endif
        } else if (move[i] == FALL) {
            /* It may be what holds a sagging neighbour (limb i-1 or i+1: the coils that
             * bend the same body section) up: kept warm while one sags, for at most
             * CTL_SAG_WAIT_MS in this step (with several limbs held one of them nearly always
             * sags, and a falling coil kept warm for good would never cross). A limb further
             * away does not wait: its coil barely moves that end. */
            w = WANT_RELEASE;
            if (SAG_NEAR(sagging, i) != 0u && ctl_limb[i].ticks < TICKS(CTL_SAG_WAIT_MS)) {
                ctl_limb[i].ticks++;
                w = WANT_HOLD;
            }
#ifdef CFG_STROKE_FALL_LEAD
            if (!rising && lead_down && i != CFG_STROKE_FALL_LEAD && FROM_STROKE(i, level) &&
                ctl_limb[i].clock < TICKS(CTL_FALL_WAIT_MS)) {
                /* all falling from strokes: held at its stroke until the fall lead is down (ctl.h) */
                w = ABOVE_HOLD(i, (uint8_t)(level - 1u), level) ? WANT_NOTHING : WANT_HEAT;
            }
#endif
        } else if (move[i] == SAG) {
            w = WANT_HEAT + ctl_limb[i].boost;
#ifdef CFG_LIMB_STROKE_CDEG
            if (CLIMBS_TO_STROKE(i, level) && got[i] > least + CTL_SHARE_SYNC &&
                ctl_limb[i].clock < TICKS(CTL_CLIMB_MAX_MS)) {
                w = WANT_HOLD;          /* ahead of another limb's climb: wait for it (ctl.h) */
                ctl_limb[i].ticks = 0u; /* not hovering: waiting */
                waiting = 1;
            } else if (CLIMBS_TO_STROKE(i, level) && got[i] > stopped + CTL_SHARE_SYNC &&
                       ctl_limb[i].ticks > TICKS(CTL_CLIMB_STOP_MS / 2u)) {
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
#ifdef CFG_LIMB_STROKE_CDEG
        /* The knee watch (ctl.h, CTL_KNEE_MS) of a limb the step raises to its stroke; a limb
         * whose coil it found spent is kept at the hold duty in the rest of the step: cut down to
         * it from the drive duty, and raised to it from off where the limb sits at its level (a
         * spent coil cooling off let its end fall out of the order the ratchet needs). */
        if ((move[i] == RISE && CLIMBS_TO_STROKE(i, target[i])) || (move[i] == SAG && CLIMBS_TO_STROKE(i, level)) ||
            ctl_limb[i].spent) {
            if (stall_knee(i, (uint8_t)(w >= WANT_HEAT && !sma_cooling(ctl_limb_actuator(i)))) && (w >= WANT_HEAT || (move[i] != RISE && level != PSI_UNKNOWN))) {
                w = WANT_HOLD;
            }
        }
#endif
        if (level != PSI_UNKNOWN) {
            stall_watch(i, target[i], level, (uint8_t)(w >= WANT_HEAT && move[i] == RISE), to_go[i]);
            /* Its coil heating and not held off by the envelope, its ψ stopped answering (ctl.h):
             * - rising alone (the body couples limbs that move together), short of its level:
             *   it cannot get there, as after CTL_STALL_MS without progress but at once;
             * - with the hold watch, heating below its hold edge at its level, relaxed (it never
             *   settled clear of that edge) and settled clear of its band, or not settled yet
             *   after rising into its level in this step (SAG_STOPPED): held where it stopped,
             *   its coil off until it sags CTL_CLIMB_CDEG below its highest. Not settled, it
             *   settles in its level there if past ψ* (psi_settle_in_level): its coil has given
             *   all it has. The watch's count runs on from the rise, so the coil is off a reach
             *   time after the last gain, not a hover time and a reach time. A limb settled by the
             *   margins (stall NONE) is held by the bang-bang hold alone. */
            if (REACH_WATCH && w >= WANT_HEAT &&
                (move[i] == RISE ? changing == 1u
                                 : HOLD_WATCH && move[i] == SAG &&
                                       (PSI_IN_LEVEL ? ctl_limb[i].stall == CTL_STALL_OSCILLATING || !psi_settled(i) || RISEN(i)
                                                     : ctl_limb[i].stall == CTL_STALL_OSCILLATING && psi_settled(i)))) {
                if (sma_cooling(ctl_limb_actuator(i))) {
                    ctl_limb[i].still = NOT_SEEN; /* held off: it starts over, from a cooler coil */
                } else if (stall_at_reach(i, &ctl_limb[i]) && move[i] == RISE) {
                    ctl_limb[i].stall = CTL_STALL_UNREACHABLE;
                } else if (ctl_limb[i].still == REACH_LOOKS && move[i] == SAG && SAG_STOPPED(i)) {
                    w = WANT_NOTHING;
#if PSI_IN_LEVEL
                    if (ctl_limb[i].stall == CTL_STALL_NONE) {
                        ctl_limb[i].stall = CTL_STALL_OSCILLATING; /* decided for this step (stall_watch) */
                        psi_relax(i, PSI_RELAX_EDGES);
                    }
                    if (ctl_look == 0u && !psi_settled(i)) {
                        psi_settle_in_level(i); /* an atan2: once a look, not each tick it is held off */
                    }
#endif
                }
            }
            if (ctl_limb[i].stall == CTL_STALL_UNREACHABLE && move[i] == RISE) {
                w = WANT_NOTHING; /* cannot get there: stop heating, let it cool */
            }
#if CTL_HELD_UP
            held_up |= (uint8_t)(move[i] == FALL && ctl_limb[i].held_up >= TICKS(CTL_FALL_STALL_MS));
#endif
        }
        a = ctl_limb_actuator(i);
        if (w > want[a]) {
            want[a] = w;
        }
    }
    /* Without CTL_BOOST_MS no limb is ever boosted (boost stays 0: WANT_HEAT is the strongest
     * want), so the ceiling's case is compiled out and heat is "at least WANT_HEAT": the same
     * duties, 24 B smaller on the Nano (R1 measured without its boost). */
#if CTL_HELD_UP
    hold_low = held_up; /* the holds of the next tick */
#endif
#ifdef CFG_LIMB_STROKE_CDEG
    ctl_waited = waiting;
    /* safety: a coil the knee watch found spent is through its transformation whichever limb
     * asks for it: with a run-time map that puts two limbs on one coil (SET_ACTUATOR_MAP [0, 0]),
     * the other limb's rise kept it at the drive duty, the knee watch of a limb whose ψ the coil
     * moves only through the body never armed, and R1-stroke's left coil reached 167 °C (210 °C
     * at power 1.3), no fault latched. Kept at the hold duty for every limb on it. */
    for (i = 0; i < CFG_N_LIMBS; i++) {
        uint8_t a = ctl_limb_actuator(i);
        if (ctl_limb[i].spent && want[a] > WANT_HOLD) {
            want[a] = WANT_HOLD;
        }
    }
#endif
#if KNEE_COIL
    /* safety: the coil-wide knee (ctl.h, CTL_KNEE_MS). A coil asked for the drive duty, by
     * whichever limb, is watched through every limb on it; once one of them, seen moving fast
     * in this heat, stops, the coil is through its transformation and kept at the hold duty
     * for the rest of the robot step (or until that limb drops a level: stall_watch). The
     * one-actuator R1 worn by 14,758 cycles: its coil bent its own (left) end to 50.4° and
     * stopped, and was heated on at the drive duty for the right end, which it lifts only
     * through the body, creeping by tenths inside its band: 0.75 s, to 136 °C, before the hold
     * watch cut it (docs/control.md, "The knee"). A limb's own want is left as it is, so the
     * reach and hold watches still see it heating and cut or settle it as before, from a coil
     * that no longer heats past its transformation. */
    for (i = 0; i < CFG_N_LIMBS; i++) {
        uint8_t a = ctl_limb_actuator(i);
        if (psi_level(i) != PSI_UNKNOWN &&
            stall_knee(i, (uint8_t)(want[a] >= WANT_HEAT && !sma_cooling(a))) && want[a] >= WANT_HEAT) {
            want[a] = WANT_HOLD;
        }
    }
#endif
#if SEQ_CLOCK_PAUSE
    if (ctl_look == FALL_LOOK) {
        fall_down = stall_fall_watch(target);
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
