/* fallback.h - an actuator lost: which one, and going on without it.
 *
 * Contract. fallback_fault() is told every fault the firmware raises; for STATE_TIMEOUT (the
 * coil of the limb off its target) and SMA_ON_LIMIT (that coil) it names the actuator it suspects
 * and the failed transition (EVENT SUSPECT). With CFG_FALLBACK (robot file [control]
 * fallback, on by default) and a fallback gait for that actuator and the running direction
 * (gait_table.c, proleg.limbloss), it then switches by itself, once until the coil is
 * taken back (limbmap.h: SET_ACTUATOR_MAP with no entries, or a reset): the map
 * becomes the fallback's, the fallback gait is loaded (it replaces a LOAD_GAIT gait) and
 * started from the measured state, the fault is cleared, and EVENT FALLBACK + GAIT_STARTED
 * say so. A second loss, one without a fallback, or one in a loaded gait whose way START left
 * unstated (PROTO_DIR_UNSTATED: a learning probe walks neither way) stays latched for the host.
 */
#ifndef PROLEG_FALLBACK_H
#define PROLEG_FALLBACK_H

#include <stdint.h>

#include "robot_config.h"
#include "rom.h"

#define FALLBACK_MAX_STEPS 16u /* proleg.firmware.gaits.MAX_FALLBACK_STEPS */

#if CFG_FALLBACK
/* Rendered in gait_table.c: per (lost actuator, direction +x/-x) the map and the gait. */
extern const uint8_t limbmap_fb_map[][CFG_N_LIMBS] ROM;
extern const cfg_state_t limbmap_fb_steps[] ROM;
extern const uint16_t limbmap_fb_first[] ROM;
extern const uint8_t limbmap_fb_len[] ROM;
#endif

/* A fault was raised (fault.c): suspect, report, maybe fall back (see above). */
void fallback_fault(uint8_t code, uint16_t detail);

#endif /* PROLEG_FALLBACK_H */
