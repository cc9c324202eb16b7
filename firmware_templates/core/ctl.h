/* ctl.h - from (measured levels, target levels) to a duty per actuator.
 *
 * Contract, per limb: target above its level → its actuator at the drive duty (heat,
 * ψ rises); target below → off (the body's elasticity lowers ψ); holding a level L ≥ 1
 * → bang-bang on the hold edge of threshold L−1 (its upper band edge plus
 * CFG_HOLD_MARGIN_CDEG): heat while the last sample is below it, off at or above it, so
 * each on-burst is short; holding level 0 → off.
 * An actuator that drives several limbs takes the largest demand of its limbs (it heats
 * if any of them must go up). Levels come from psi.h.
 */
#ifndef PROLEG_CTL_H
#define PROLEG_CTL_H

#include <stdint.h>

#include "robot_config.h"

/* target[i]: wanted level of limb i; duty[a]: result for actuator a (permyriad). */
void ctl_demand(const uint8_t target[CFG_N_LIMBS], uint16_t drive_pm, uint16_t duty[CFG_N_ACTUATORS]);

/* Actuator index driving limb i. */
uint8_t ctl_limb_actuator(uint8_t limb);

#endif /* PROLEG_CTL_H */
