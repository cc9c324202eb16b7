/* limbmap.h - which actuator raises each limb, a run-time setting.
 *
 * Contract. The map starts as the build's (robot file: each limb's `actuator`) and can be
 * changed while no gait runs (SET_ACTUATOR_MAP): any actuator of the build per limb. It only
 * says which coil the controller heats for a limb; the safety envelope (duty, on-time,
 * cool-down, thermal budget: sma.c) stays per actuator and is never widened by a map.
 * Limb loss (switching to a fallback map): fallback.h. A fallback's map serves the fallback
 * gait (and gaits the host loads) only: START of a built-in gait is refused while a coil is
 * given up (NACK NOT_ALLOWED, detail 3: cmd.c), and SET_ACTUATOR_MAP with no entries (or a
 * reset) takes it back, the build's map again: the operator's word that the coil was wrongly
 * suspected, or has been mended. START used to go back to the build's map by itself: a host
 * restarting gait 0 every few seconds heated a dead coil up to the state timeout at every
 * START, 58-73 % of the time, each fault ending in another fallback instead of a latch.
 * A fallback that leaves a limb on its lost coil keeps that coil in the map: drive.c holds a
 * given-up coil off in such builds (CFG_FALLBACK_KEEPS_LOST).
 */
#ifndef PROLEG_LIMBMAP_H
#define PROLEG_LIMBMAP_H

#include <stdint.h>

#include "robot_config.h"
#include "rom.h"

#define LIMBMAP_NONE 0xFFu

void limbmap_init(void);
uint8_t limbmap_actuator(uint8_t limb);
/* The actuator the fallback gave up (LIMBMAP_NONE: none). */
uint8_t limbmap_lost(void);
/* Nonzero for a limb whose own actuator (the build's map) the fallback gave up: the fallback
 * lifts it, if at all, through the body with another limb's coil. */
uint8_t limbmap_given_up(uint8_t limb);
/* n == 0: the build's map. Returns 0, or a PROTO_ERR_* with *bad = offending limb (0xFFFF:
 * not one entry per limb). The caller refuses it while a gait runs. */
uint8_t limbmap_set(const uint8_t *actuators, uint8_t n, uint16_t *bad);
/* Run with the map at rom_map (ROM, one actuator per limb), lost_actuator given up. */
void limbmap_use(uint8_t lost_actuator, const uint8_t *rom_map);

#endif /* PROLEG_LIMBMAP_H */
