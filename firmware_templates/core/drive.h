/* drive.h - sequencing glue: measured state -> sequencer -> duties -> safety envelope.
 *
 * Contract. drive_step() runs once per tick after imucheck_read(): while a gait runs and
 * the robot state is known, it shows the sequencer the measured state once every limb
 * is settled (psi_settled) and otherwise a state that is not the target, reports each
 * reached step (EVENT STATE_REACHED) and turns a state timeout into a latched fault
 * naming the first limb off its level (DRIVE_NO_LIMB when every limb is at its level and
 * one would not settle: no coil is suspected then). drive_apply() then asks the controller (ctl.h)
 * for the target's duties (every duty 0 when idle, faulted, e-stopped or the state is
 * unknown), applies them through sma.h and reports each actuator forced into cool-down
 * (EVENT FAULT SMA_ON_LIMIT, reported, not latched) - unless the step guard (safety.h)
 * latches a fault: repeated on-limit hits on one step, or the state timeout on real time
 * from the first demand (STOP/START do not reset it). drive_started() records the gait and
 * direction last started, for telemetry, and starts the step guard's record of which coils
 * heated on the way to the next target afresh (safety.h).
 */
#ifndef PROLEG_DRIVE_H
#define PROLEG_DRIVE_H

#include <stdint.h>

#define DRIVE_NO_LIMB 0xFFu /* STATE_TIMEOUT's detail: every limb at its level, one unsettled */

void drive_init(void);
void drive_step(void);
void drive_apply(void);

void drive_started(uint8_t gait, uint8_t dir);
uint8_t drive_gait(void);
uint8_t drive_dir(void);

#endif /* PROLEG_DRIVE_H */
