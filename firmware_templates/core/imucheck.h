/* imucheck.h - the limbs' IMUs: start, read, check, classify into the robot state.
 *
 * Contract. imucheck_start(limb) wakes and checks one MPU-6050 (WHO_AM_I, config);
 * a bus error latches IMU_NO_ACK, a wrong answer IMU_BAD_DATA (fault.h), and the limb
 * is marked bad. imucheck_read() runs once per tick: for each limb not marked bad it
 * reads the accelerometer (6 bytes) and faults the limb on no ACK twice in a row, |g|
 * outside 0.5..1.5 g, or identical samples CFG_IMU_STUCK_SAMPLES times in a row; a good
 * sample goes to the ψ classifier (psi.h). The measured robot state is the state index
 * of every limb's debounced level, or IMUCHECK_UNKNOWN while any limb has none or is bad.
 * A bad limb is not read again until imucheck_take_bad() hands its bit to CLEAR(FAULTS).
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
void imucheck_start(uint8_t limb);
void imucheck_read(void);

/* The debounced robot state (seq_state_index), or IMUCHECK_UNKNOWN. */
uint32_t imucheck_measured(void);

/* Bit per limb: the IMU is marked bad. */
uint8_t imucheck_bad(void);

/* The bad mask, cleared (the caller restarts those limbs). */
uint8_t imucheck_take_bad(void);

#endif /* PROLEG_IMUCHECK_H */
