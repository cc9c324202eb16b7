/* ctl.h - from (measured levels, target levels) to a duty per actuator.
 *
 * Contract, per limb, in order:
 * - rising (target above its level) → the drive duty: heat, ψ rises;
 * - falling (target below) → off: the body's elasticity lowers ψ;
 * - holding a level L ≥ 1 below the hold edge of threshold L−1 (its upper band edge
 *   plus CFG_HOLD_MARGIN_CDEG), i.e. sagging → the drive duty;
 * - holding any level at or above the settle edge of the threshold above (its lower
 *   band edge minus the margin), i.e. not yet clear of it → off;
 * - holding a level L ≥ 1 otherwise → the hold duty; holding level 0 → off.
 *
 * Why a hold duty: an SMA coil that cools below its martensite start temperature Ms
 * relaxes, and heating it again contracts it only once it is back above its austenite
 * start As, some 10-20 K higher (transformation hysteresis). A held limb whose coil is
 * left to cool therefore sags, and by the time ψ reaches the hold edge its coil is too
 * cold to catch it: the limb falls through ψ* while the coil re-heats. The hold duty
 * keeps the coil warm between Ms and As, where it neither relaxes nor contracts further;
 * ψ feedback on the hold edge still corrects any sag. 0 turns it off.
 *
 * Steps that change several limbs at once (the friction states must change together,
 * or the robot makes two transitions with other rewards):
 * - all rising: a limb ahead of the farthest one by more than CTL_SYNC_CDEG waits at
 *   the hold duty, so that they cross together even when their coils start at
 *   different temperatures;
 * - some falling: a rising limb climbs to CTL_SYNC_ZONE_CDEG below its crossing and
 *   waits there until every falling limb is within CTL_SYNC_CDEG of its own; a falling
 *   limb is never held back for this (that would mean re-heating its coil).
 * - While any held raised limb sags, falling limbs wait at the hold duty: through the
 *   body they may be what holds it up (a step like 11 → 01 on coupled coils), and a
 *   coil kept warm stops relaxing until the sagging limb's own coil has caught it.
 *
 * An actuator that drives several limbs serves the strongest demand of its limbs: heat
 * over release over hold. Levels come from psi.h.
 */
#ifndef PROLEG_CTL_H
#define PROLEG_CTL_H

#include <stdint.h>

#include "robot_config.h"

/* Synchronised steps (see above), in 0.01°. */
#define CTL_SYNC_CDEG 200
#define CTL_SYNC_ZONE_CDEG 600

/* target[i]: wanted level of limb i; drive_pm, hold_pm and duty[a], the result for
 * actuator a: permyriad. */
void ctl_demand(const uint8_t target[CFG_N_LIMBS], uint16_t drive_pm, uint16_t hold_pm,
                uint16_t duty[CFG_N_ACTUATORS]);

/* Actuator index driving limb i. */
uint8_t ctl_limb_actuator(uint8_t limb);

#endif /* PROLEG_CTL_H */
