/* ctl.c - see ctl.h. */
#include "ctl.h"

#include "psi.h"
#include "rom.h"

static const uint8_t limb_actuator[CFG_N_LIMBS] ROM = CFG_LIMB_ACTUATOR;

uint8_t ctl_limb_actuator(uint8_t limb)
{
    return ROM_U8(&limb_actuator[limb]);
}

void ctl_demand(const uint8_t target[CFG_N_LIMBS], uint16_t drive_pm, uint16_t duty[CFG_N_ACTUATORS])
{
    uint8_t i;
    for (i = 0; i < CFG_N_ACTUATORS; i++) {
        duty[i] = 0;
    }
    for (i = 0; i < CFG_N_LIMBS; i++) {
        uint8_t level = psi_level(i);
        uint8_t want = target[i];
        uint8_t heat;
        if (level == PSI_UNKNOWN) {
            heat = 0;
        } else if (want > level) {
            heat = 1;
        } else if (want < level || level == 0u) {
            heat = 0;
        } else {
            heat = !psi_last_at_or_above_hold(i, (uint8_t)(level - 1u));
        }
        if (heat) {
            duty[ctl_limb_actuator(i)] = drive_pm;
        }
    }
}
