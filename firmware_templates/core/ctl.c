/* ctl.c - see ctl.h. */
#include "ctl.h"

#include "psi.h"
#include "rom.h"

static const uint8_t limb_actuator[CFG_N_LIMBS] ROM = CFG_LIMB_ACTUATOR;

/* What a limb asks of its actuator, weakest first; an actuator serves the strongest. */
enum { WANT_NOTHING, WANT_HOLD, WANT_RELEASE, WANT_HEAT };
/* A limb's part in the current step. */
enum { STAY, RISE, FALL };

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
    uint8_t moving = 0, falling = 0, sagging = 0;
    int16_t farthest = -32767, farthest_fall = -32767;
    uint8_t i;

    for (i = 0; i < CFG_N_LIMBS; i++) {
        uint8_t level = psi_level(i);
        move[i] = STAY;
        to_go[i] = 0;
        if (level == PSI_UNKNOWN || target[i] == level) {
            if (level != PSI_UNKNOWN && level > 0u && !psi_last_at_or_above_hold(i, (uint8_t)(level - 1u))) {
                sagging = 1;
            }
            continue;
        }
        move[i] = target[i] > level ? RISE : FALL;
        to_go[i] = psi_to_cross(i, move[i] == RISE ? level : (uint8_t)(level - 1u), (uint8_t)(move[i] == RISE));
        moving++;
        if (to_go[i] > farthest) {
            farthest = to_go[i];
        }
        if (move[i] == FALL) {
            falling = 1;
            if (to_go[i] > farthest_fall) {
                farthest_fall = to_go[i];
            }
        }
    }

    for (i = 0; i < CFG_N_ACTUATORS; i++) {
        want[i] = WANT_NOTHING;
    }
    for (i = 0; i < CFG_N_LIMBS; i++) {
        uint8_t level = psi_level(i);
        uint8_t w;
        if (move[i] == RISE) {
            /* Rising with others (ctl.h): wait at the hold duty while ahead of the
             * farthest, or, if some limb falls, in the zone below the crossing until
             * every falling limb is about to cross. */
            uint8_t wait = falling ? to_go[i] <= CTL_SYNC_ZONE_CDEG && farthest_fall > CTL_SYNC_CDEG
                                   : to_go[i] + CTL_SYNC_CDEG < farthest;
            w = moving > 1u && wait ? WANT_HOLD : WANT_HEAT;
        } else if (move[i] == FALL) {
            w = sagging ? WANT_HOLD : WANT_RELEASE; /* it may be what holds a sagging limb up */
        } else if (level == PSI_UNKNOWN) {
            w = WANT_NOTHING;
        } else if (level > 0u && !psi_last_at_or_above_hold(i, (uint8_t)(level - 1u))) {
            w = WANT_HEAT; /* sagging */
        } else if (level + 1u < psi_levels(i) && psi_last_at_or_above_settle(i, level)) {
            w = WANT_RELEASE; /* not yet settled clear of the level above */
        } else {
            w = level > 0u ? WANT_HOLD : WANT_NOTHING;
        }
        if (w > want[ctl_limb_actuator(i)]) {
            want[ctl_limb_actuator(i)] = w;
        }
    }
    for (i = 0; i < CFG_N_ACTUATORS; i++) {
        duty[i] = want[i] == WANT_HEAT ? drive_pm : want[i] == WANT_HOLD ? hold_pm : 0u;
    }
}
