/* imucheck.h - the limbs' IMUs: start, read, check, classify into the robot state.
 *
 * Contract. Nothing here waits on the bus: every IMU transaction (with its multiplexer
 * select, if any) is begun with imubus_begin and collected with imubus_poll (bounded by
 * the HAL's per-transaction deadline). imucheck_service() (at the tick and from the main
 * loop's idle wait) keeps one transaction on the bus, limbs in turn; a limb is begun again
 * only after imucheck_read() (once per tick) has taken its last result, so no result is
 * dropped or overwritten and each IMU is read once a tick while the bus has the time. A
 * transaction still on the bus at the tick counts at the next tick.
 * Start-up: imucheck_power_up(limb) waits the MPU-6050's typical start-up time, then
 * runs its start-up steps (mpu6050.h), one per tick, WHO_AM_I retried until the
 * maximum start-up time plus margin; then a bus error latches IMU_NO_ACK, a wrong answer
 * IMU_BAD_DATA (fault.h), and the limb is marked bad. imucheck_start(limb) is the same
 * without the wait (CLEAR(FAULTS)). A running limb faults on no ACK twice in a row, |g|
 * outside 0.5..1.5 g, or identical samples CFG_IMU_STUCK_SAMPLES times in a row; a good
 * sample goes to the ψ classifier (psi.h). The measured robot state is the state index
 * of every limb's debounced level, or IMUCHECK_UNKNOWN while any limb has none, is
 * starting or is bad. A bad limb is not read again until imucheck_take_bad() hands its
 * bit to CLEAR(FAULTS).
 */
#ifndef PROLEG_IMUCHECK_H
#define PROLEG_IMUCHECK_H

#include <stdint.h>

#include "robot_config.h"

#if CFG_N_LIMBS > 8
#error "at most 8 limbs (one bit per limb in the IMU fault mask)"
#endif

#define IMUCHECK_UNKNOWN 0xFFFFu

void imucheck_init(void);
void imucheck_power_up(uint8_t limb);
void imucheck_start(uint8_t limb);
void imucheck_read(void);
void imucheck_service(void);

/* The debounced robot state (seq_state_index), or IMUCHECK_UNKNOWN. */
uint16_t imucheck_measured(void);

/* Bit per limb: the IMU is marked bad. */
uint8_t imucheck_bad(void);

/* The bad mask, cleared (the caller restarts those limbs). */
uint8_t imucheck_take_bad(void);

#endif /* PROLEG_IMUCHECK_H */
