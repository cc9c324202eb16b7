/* level.h - level calibration: each IMU's rest tilt, stored in non-volatile memory and
 * taken off every accelerometer sample before ψ is computed.
 *
 * Contract. At rest on flat ground with every coil cold the body lies straight on its
 * contacts, so every limb's true ψ is 0 (docs/plant.md); what an IMU reads then is its
 * mounting tilt plus the accelerometer's bias, seen as an angle. level_calibrate()
 * averages each limb's ψ (as corrected now) over LEVEL_SAMPLES ticks; the rest tilt o is
 * the offset in use plus that mean, and is stored; from then on level_apply() rotates each
 * sample (ax, az) by −o in the x–z plane (four 16×16→32 products, Q14 cos/sin) before ψ
 * is computed (imucheck.c, between the sample checks and psi_update), so a limb at rest
 * reads ψ = 0 again. A tilt beyond LEVEL_MAX_CDEG is refused (not at rest, not on flat
 * ground, or an IMU mounted too crooked to trust).
 *
 * On a slope. The ground's incline tilts each end's IMU too (the first limb's end up the
 * slope, the last one down), which no flat calibration can know. level_calibrate(1), with
 * the robot at rest on the slope, measures each limb's remaining tilt the same way and
 * applies it on top of the record, in RAM only (the ground changes; a power-on, CLEAR_LEVEL
 * or a flat calibration sets it back to 0; a reset that keeps the coils' budget keeps it). Relative to a flat calibration this is the
 * slope itself, as each end sees it; GET_LEVEL reports both.
 *
 * At rest, by itself (LEVEL_AT_REST). Between gaits the firmware watches for rest: no
 * gait, no fault, every limb at level 0, for LEVEL_REST_TICKS; meanwhile the limbs' ψ are
 * low-passed, one limb a tick. START then adds those readings to the ground in use
 * (level_at_start(): what level_calibrate(1) would measure), when a flat record is stored
 * and every limb's ground stays within LEVEL_MAX_CDEG; otherwise (not at rest that long, no
 * record, too steep) the ground in use stays. So after a flat calibration a robot started
 * at rest on a slope levels itself. A slope that changes during a gait is not seen: no limb
 * is known to be at rest then.
 *
 * Sampling waits for IMUs still starting up (up to LEVEL_WAIT_TICKS); a bad IMU, or one
 * still without a sample then, fails the calibration (result IMU).
 *
 * The record in non-volatile memory (hal_nv_*): a magic byte that carries the layout
 * version (0x4C 'L' = version 1), the limb count, one i16 offset per limb in 0.01°
 * (little-endian), CRC-16/CCITT-FALSE over all of that (little-endian). Erased (first byte
 * 0xFF; CLEAR_LEVEL erases that byte) is PROTO_LEVEL_NONE; a wrong magic, limb count or
 * CRC is PROTO_LEVEL_CORRUPT; either way the offsets are 0 and nothing is applied.
 */
#ifndef PROLEG_LEVEL_H
#define PROLEG_LEVEL_H

#include <stdint.h>

#include "robot_config.h"

/* Build switch: 0 leaves level calibration out (about 1.6 KB of AVR flash): the commands
 * are refused (NACK NOT_ALLOWED, detail 5), GET_LEVEL reports NONE, nothing is applied.
 * Set it in a board file's cflags (-DCFG_LEVEL_CALIBRATION=0). */
#ifndef CFG_LEVEL_CALIBRATION
#define CFG_LEVEL_CALIBRATION 1
#endif

#define LEVEL_MAGIC 0x4Cu /* 'L': record layout version 1 */
#define LEVEL_RECORD_BYTES (4u + 2u * CFG_N_LIMBS)
#define LEVEL_SAMPLES 64 /* ticks averaged: a power of two (the mean is a shift) */
#define LEVEL_WAIT_TICKS (2u * CFG_TICK_HZ) /* 2 s */
#define LEVEL_MAX_CDEG 2000 /* 20°: the mounting tilt a limb may have and still be trusted */
#define LEVEL_REST_TICKS (2u * CFG_TICK_HZ) /* 2 s at rest (a lowered limb's coil cools back in
                                              * about that: docs/calibration.md) */
#define LEVEL_REST_SHIFT 6                    /* the at-rest low-pass: τ = 64 of a limb's samples */
/* Build switch: 0 leaves out levelling at rest on START (level_at_start does nothing). */
#ifndef LEVEL_AT_REST
#define LEVEL_AT_REST 1
#endif

#if CFG_LEVEL_CALIBRATION
/* Load the stored record (status and offsets) and stop any calibration. kept: the reset kept
 * the coils' budget (sma_init's result): a gait that ran before it still needs its 2 s of rest
 * before a calibration (level_calibrate's -3); otherwise nothing was driven. */
void level_init(uint8_t kept);

/* Rotate a sample of `limb` by its rest tilt (nothing when none is stored). */
void level_apply(uint8_t limb, int16_t *ax, int16_t *az);

/* Begin sampling: on flat ground (0: the result is stored) or on this ground (1: applied
 * on top of the record until a power-on). 0, or -1 when a calibration or an erase is under way
 * (-2: not in this build), -3 (with LEVEL_AT_REST) when a gait ran or a fault latched since
 * the robot was last at rest LEVEL_REST_TICKS: its limbs may still be coming down (a flat
 * calibration 5 ms after STOP stored R1's falling ends, 7.6° and 17.4°, as mounting tilts,
 * and START +x was refused TOO_STEEP on flat ground from then on, across resets). */
int8_t level_calibrate(uint8_t on_this_ground);

/* Erase the record (begins the write; status NONE at once). 0, or -1 while calibrating. */
int8_t level_clear(void);

/* Move a calibration on (sampling → checks → write → verify); sends EVENT LEVEL_DONE when
 * it ends. Called once per tick (cmd_poll). */
void level_poll(void);

/* START from rest: take this ground's tilt from the readings tracked at rest (see above). */
#if LEVEL_AT_REST
void level_at_start(void);
#else
#define level_at_start() ((void)0)
#endif

#ifdef CFG_MAX_CLIMB_CDEG
/* The climb guard ([control] max_climb_deg): how far the ground in use rises in the gait's
 * direction (towards -x when `minus_x`), 0.01°, if that is more than CFG_MAX_CLIMB_CDEG
 * (walking -x: CFG_MAX_CLIMB_MX_CDEG where the robot file gives -x its own; built-in gait
 * `gait` of that way: its entry of CFG_MAX_CLIMB_GAITS_PX / _MX where the file lists one per
 * gait; PROTO_GAIT_USER, the loaded gait: the way's limit, the smallest of its list); else 0. Against
 * a flat record the first limb's end reads the slope rising towards +x and the last limb's end
 * its negative (above), so the rise is half their difference.
 * The ground in use is the one START levelled on at rest, or level_calibrate(1)'s. 0 without a
 * flat record: the ground cannot be told from the IMUs' mounting tilt. LEVEL_TOO_TILTED when
 * this START, from rest, found an end tilted beyond LEVEL_MAX_CDEG: a ground no calibration
 * takes, uphill or down (the gait would run on ψ misread by that much). Call it after
 * level_at_start(). */
#define LEVEL_TOO_TILTED 0xFFFFu
uint16_t level_too_steep(uint8_t minus_x, uint8_t gait);
#endif

/* PROTO_LEVEL_* status, and the offset in use per limb (0.01°). */
uint8_t level_status(void);
int16_t level_offset_cdeg(uint8_t limb);
int16_t level_ground_cdeg(uint8_t limb);
#else
#define level_init(kept) ((void)(kept))
#define level_apply(limb, ax, az) ((void)0)
#define level_calibrate(on_this_ground) ((void)(on_this_ground), (int8_t)-2)
#define level_clear() ((int8_t)-2)
#define level_poll() ((void)0)
#define level_at_start() ((void)0)
#define level_status() ((uint8_t)0) /* PROTO_LEVEL_NONE */
#define level_offset_cdeg(limb) ((void)(limb), (int16_t)0)
#define level_ground_cdeg(limb) ((void)(limb), (int16_t)0)
#define level_too_steep(minus_x, gait) ((void)(minus_x), (void)(gait), (uint16_t)0)
#endif

#endif /* PROLEG_LEVEL_H */
