/* Shared by the host unit tests of core/ctl.c and core/stall.c: a limb's accelerometer sample
 * for an angle, a fresh controller, and the duties the tests ask for. */
#ifndef CTL_UNIT_H
#define CTL_UNIT_H

#include <math.h>

#include "ctl.h"
#include "limbmap.h"
#include "psi.h"

#define PI_D 3.14159265358979323846
#define DRIVE 6000u
#define HOLD 2500u

/* Feed limb `limb` a sample at ψ = `deg` (0.5 g: the magnitude does not matter). */
static inline void put(uint8_t limb, double deg)
{
    psi_update(limb, (int16_t)lround(8192.0 * sin(deg * PI_D / 180.0)),
               (int16_t)lround(8192.0 * cos(deg * PI_D / 180.0)));
}

/* The rendered thresholds, no debounce, the built limb map, no history. */
static inline void setup(void)
{
    psi_init();
    psi_set_debounce(1);
    limbmap_init();
    ctl_reset();
}

#if CFG_N_LIMBS == 2
/* The controller's duties for target levels (t0, t1) of a two-limb robot. */
static inline void demand(uint8_t t0, uint8_t t1, uint16_t duty[CFG_N_ACTUATORS])
{
    uint8_t target[CFG_N_LIMBS];
    target[0] = t0;
    target[1] = t1;
    ctl_demand(target, DRIVE, HOLD, duty);
}
#endif

#endif /* CTL_UNIT_H */
