/* ctl.c - see ctl.h. */
#include "ctl.h"

#include <string.h>

#include "limbmap.h"
#include "psi.h"
#include "rom.h"

/* What a limb asks of its actuator, weakest first; an actuator serves the strongest. */
enum { WANT_NOTHING, WANT_HOLD, WANT_RELEASE, WANT_HEAT, WANT_BOOST };
/* A limb's part in the current step. */
enum { STAY, RISE, FALL, SAG };

/* Held limbs sagging below their hold edge, for the falling limbs' wait: bit i+1 is limb i, so
 * a falling limb i looks at its neighbours i-1 and i+1 (bits i and i+2). With two limbs the
 * other one is the only neighbour: one flag, the same rule, no bytes spent on the Nano. */
#if CFG_N_LIMBS > 2
typedef uint16_t sag_t;
#define SAG_MARK(i) ((sag_t)(2u << (i)))
#define SAG_NEAR(s, i) (((s) >> (i)) & 5u)
#else
typedef uint8_t sag_t;
#define SAG_MARK(i) 1u
#define SAG_NEAR(s, i) (s)
#endif

#define TICKS(ms) ((uint16_t)(((uint32_t)(ms) * CFG_TICK_HZ + 999u) / 1000u))

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
} ctl_limb_t;

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
        psi_relax(i, 0);
    }
    if (level != c->level) {
        c->ticks = 0; /* a new level: the hover and stall clocks restart */
        if (c->level != PSI_UNKNOWN && c->crossings < CTL_OSC_CROSSINGS) {
            c->crossings++;
        }
        c->level = level;
    }
    if (c->stall != CTL_STALL_NONE) {
        return; /* decided for this step */
    }
    if (level == target) {
        if (psi_settled(i)) {
            c->ticks = 0;
        } else if (++c->ticks > TICKS(CTL_HOVER_MS) || c->crossings >= CTL_OSC_CROSSINGS) {
            c->stall = CTL_STALL_OSCILLATING;
            psi_relax(i, 1);
        }
    } else if (heating) {
        if (progress < c->best) {
            c->best = progress;
            c->ticks = 0;
        } else if (++c->ticks >= TICKS(CTL_STALL_MS)) {
            c->stall = CTL_STALL_UNREACHABLE;
        }
    }
}

void ctl_demand(const uint8_t target[CFG_N_LIMBS], uint16_t drive_pm, uint16_t hold_pm,
                uint16_t duty[CFG_N_ACTUATORS])
{
    uint8_t want[CFG_N_ACTUATORS];
    uint8_t move[CFG_N_LIMBS];
    int16_t to_go[CFG_N_LIMBS];
    uint8_t falling = 0, far_fall = 0;
    sag_t sagging = 0;
    int16_t farthest = -1;
    uint8_t i;

    for (i = 0; i < CFG_N_LIMBS; i++) {
        uint8_t level = psi_level(i);
        move[i] = STAY;
        to_go[i] = 0;
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
                if (!psi_last_at_or_above_hold(i, thr)) {
                    cl[i].heat = 1;
                    sagging |= SAG_MARK(i);
                } else if (psi_last_at_or_above_hold_top(i, thr)) {
                    cl[i].heat = 0;
                }
                if (cl[i].heat) {
                    move[i] = SAG;
                }
            }
            continue;
        }
        move[i] = target[i] > level ? RISE : FALL;
        to_go[i] = psi_to_go_cdeg(i, move[i] == RISE ? level : (uint8_t)(level - 1u), (uint8_t)(move[i] == RISE));
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
            w = wait ? WANT_HOLD : WANT_HEAT + cl[i].boost;
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
        } else if (move[i] == SAG) {
            w = WANT_HEAT + cl[i].boost;
        } else if (level == PSI_UNKNOWN) {
            w = WANT_NOTHING;
        } else if (!psi_settled(i)) {
            w = WANT_RELEASE; /* not yet settled clear of the level above */
        } else {
            w = WANT_NOTHING; /* held level between hold edge and top: coil off (bang-bang) */
        }
        if (level != PSI_UNKNOWN) {
            watch(i, target[i], level, (uint8_t)(w >= WANT_HEAT && move[i] == RISE), to_go[i]);
            if (cl[i].stall == CTL_STALL_UNREACHABLE && move[i] == RISE) {
                w = WANT_NOTHING; /* cannot get there: stop heating, let it cool */
            }
        }
        a = ctl_limb_actuator(i);
        if (w > want[a]) {
            want[a] = w;
        }
    }
    for (i = 0; i < CFG_N_ACTUATORS; i++) {
        duty[i] = want[i] == WANT_BOOST ? (uint16_t)CFG_MAX_DUTY_PM : want[i] == WANT_HEAT ? drive_pm : want[i] == WANT_HOLD ? hold_pm : 0u;
    }
}
