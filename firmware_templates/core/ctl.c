/* ctl.c - see ctl.h. */
#include "ctl.h"

#include "psi.h"
#include "rom.h"

static const uint8_t limb_actuator[CFG_N_LIMBS] ROM = CFG_LIMB_ACTUATOR;

/* What a limb asks of its actuator, weakest first; an actuator serves the strongest. */
enum { WANT_NOTHING, WANT_HOLD, WANT_RELEASE, WANT_HEAT };
/* A limb's part in the current step. */
enum { STAY, RISE, FALL, SAG };

uint8_t ctl_limb_actuator(uint8_t limb)
{
    return ROM_U8(&limb_actuator[limb]);
}

void ctl_demand(const uint8_t target[CFG_N_LIMBS], uint16_t drive_pm, uint16_t hold_pm,
                uint16_t duty[CFG_N_ACTUATORS])
{
    uint8_t want[CFG_N_ACTUATORS];
    uint8_t move[CFG_N_LIMBS];
    int16_t to_go[CFG_N_LIMBS];
    uint8_t falling = 0, sagging = 0, far_fall = 0;
    int16_t farthest = -32767;
    uint8_t i;

    for (i = 0; i < CFG_N_LIMBS; i++) {
        uint8_t level = psi_level(i);
        move[i] = STAY;
        to_go[i] = 0;
        if (level == PSI_UNKNOWN) {
            continue;
        }
        if (target[i] == level) {
            if (level > 0u && !psi_last_at_or_above_hold(i, (uint8_t)(level - 1u))) {
                move[i] = SAG;
                sagging = 1;
            }
            continue;
        }
        move[i] = target[i] > level ? RISE : FALL;
        to_go[i] = psi_to_cross(i, move[i] == RISE ? level : (uint8_t)(level - 1u), (uint8_t)(move[i] == RISE));
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
            /* Rising with others (ctl.h): wait at the hold duty while ahead of the
             * farthest (never true when rising alone), or, if some limb falls, in the
             * zone below the crossing until every falling limb is about to cross. */
            uint8_t wait = falling ? to_go[i] <= CTL_SYNC_ZONE_CDEG && far_fall
                                   : to_go[i] + CTL_SYNC_CDEG < farthest;
            w = wait ? WANT_HOLD : WANT_HEAT;
        } else if (move[i] == FALL) {
            w = sagging ? WANT_HOLD : WANT_RELEASE; /* it may be what holds a sagging limb up */
        } else if (move[i] == SAG) {
            w = WANT_HEAT;
        } else if (level == PSI_UNKNOWN) {
            w = WANT_NOTHING;
        } else if (!psi_settled(i)) {
            w = WANT_RELEASE; /* not yet settled clear of the level above */
        } else {
            w = level > 0u ? WANT_HOLD : WANT_NOTHING;
        }
        a = ctl_limb_actuator(i);
        if (w > want[a]) {
            want[a] = w;
        }
    }
    for (i = 0; i < CFG_N_ACTUATORS; i++) {
        duty[i] = want[i] == WANT_HEAT ? drive_pm : want[i] == WANT_HOLD ? hold_pm : 0u;
    }
}
