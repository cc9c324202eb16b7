/* initzero.h - a module's state zeroed at init, where it is not zero already.
 *
 * Contract. C starts every object of static storage duration at zero before main(). On a
 * board whose main() is core/main.c, app_init runs once per reset, after that: an init then
 * has nothing to zero (CFG_INIT_ONCE = 1, robot_config.h: INIT_ZERO does nothing, and the
 * image is smaller: R1 on the Nano by about 150 B). Where a host calls app_init again on the
 * state its last run left (host-sim's sim_reset) or calls a module's init between cases (the
 * host unit tests, whose robot_config.h has no CFG_INIT_ONCE), INIT_ZERO clears the object,
 * so every init leaves its module as a reset would. An init sets what starts non-zero itself.
 */
#ifndef PROLEG_INITZERO_H
#define PROLEG_INITZERO_H

#include <string.h>

#include "robot_config.h"

#ifndef CFG_INIT_ONCE
#define CFG_INIT_ONCE 0
#endif

#if CFG_INIT_ONCE
#define INIT_ZERO(obj) ((void)0)
#else
#define INIT_ZERO(obj) memset(&(obj), 0, sizeof(obj))
#endif

/* NOINIT: an object the C runtime leaves as it was at reset (the .noinit section of the AVR
 * and STM32 link scripts), for state kept across a reset that is not a power-on; its init
 * decides whether to trust it (sma.c). Host builds keep every global across their resets. */
#if defined(__AVR__) || defined(__arm__)
#define NOINIT __attribute__((section(".noinit")))
#else
#define NOINIT
#endif

#endif /* PROLEG_INITZERO_H */
