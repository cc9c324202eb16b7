/* level.c - see level.h. */
#include "level.h"

#include "crc16.h"
#include "fault.h"
#include "hal.h"
#include "imucheck.h"
#include "proto.h"
#include "psi.h"
#include "seq.h"
#include "tx.h"

#define PH_IDLE 0u
#define PH_SAMPLING 1u
#define PH_WRITING 2u
#define CRC_AT (LEVEL_RECORD_BYTES - 2u)

static uint8_t status;   /* PROTO_LEVEL_NONE / STORED / CORRUPT */
static uint8_t phase;
static uint8_t clearing; /* the write in flight erases the record */
static uint8_t left;     /* ticks of sampling left */
static uint16_t waited;  /* ticks some limb had no sample yet */
static uint8_t ground_mode; /* the calibration under way levels on this ground (RAM only) */
static int32_t sum[CFG_N_LIMBS]; /* ψ as corrected now, 0.01°, summed over the ticks */
static int16_t ground[CFG_N_LIMBS]; /* this ground's tilt on top of the record, 0.01° */
static int16_t rc[CFG_N_LIMBS], rs[CFG_N_LIMBS]; /* Q14 cos/sin of each rest tilt */
static uint8_t rec[LEVEL_RECORD_BYTES];          /* the record (hal_nv_write keeps the pointer) */

static uint16_t rec_crc(void)
{
    return crc16_ccitt(CRC16_INIT, rec, CRC_AT);
}

int16_t level_offset_cdeg(uint8_t limb)
{
    return status == PROTO_LEVEL_STORED ? (int16_t)(uint16_t)(rec[2u + 2u * limb] | ((uint16_t)rec[3u + 2u * limb] << 8)) : 0;
}

/* Read the record back: status, then each limb's rotation (none unless it is valid). */
static void load(void)
{
    uint8_t i;
    uint16_t crc;
    hal_nv_read(rec, LEVEL_RECORD_BYTES);
    crc = rec_crc();
    status = rec[0] == 0xFFu ? PROTO_LEVEL_NONE
             : (rec[0] == LEVEL_MAGIC && rec[1] == CFG_N_LIMBS && rec[CRC_AT] == (uint8_t)crc &&
                rec[CRC_AT + 1u] == (uint8_t)(crc >> 8))
                 ? PROTO_LEVEL_STORED
                 : PROTO_LEVEL_CORRUPT;
    for (i = 0; i < CFG_N_LIMBS; i++) {
        rc[i] = psi_cos_q14((int16_t)(level_offset_cdeg(i) + ground[i]));
        rs[i] = psi_sin_q14((int16_t)(level_offset_cdeg(i) + ground[i]));
    }
}

int16_t level_ground_cdeg(uint8_t limb)
{
    return ground[limb];
}

void level_init(void)
{
    phase = PH_IDLE;
    load();
}

void level_apply(uint8_t limb, int16_t *ax, int16_t *az)
{
    int16_t x = *ax, z = *az, c = rc[limb], s = rs[limb];
    if (s != 0) { /* a tilt of 0.01° already has sin ≥ 2 in Q14; 16×16→32 products */
        *ax = (int16_t)(((int32_t)x * c - (int32_t)z * s) >> 14);
        *az = (int16_t)(((int32_t)z * c + (int32_t)x * s) >> 14);
    }
}

int8_t level_calibrate(uint8_t on_this_ground)
{
    uint8_t i;
    if (phase != PH_IDLE) {
        return -1;
    }
    for (i = 0; i < CFG_N_LIMBS; i++) {
        sum[i] = 0;
    }
    ground_mode = on_this_ground;
    left = LEVEL_SAMPLES;
    waited = 0;
    clearing = 0;
    phase = PH_SAMPLING;
    return 0;
}

static void write(uint8_t n)
{
    phase = hal_nv_write(rec, n) == 0 ? PH_WRITING : PH_IDLE;
}

int8_t level_clear(void)
{
    uint8_t i;
    if (phase != PH_IDLE) {
        return -1;
    }
    rec[0] = 0xFFu; /* the erased magic: no record */
    status = PROTO_LEVEL_NONE;
    for (i = 0; i < CFG_N_LIMBS; i++) {
        ground[i] = 0;
    }
    clearing = 1;
    write(1);
    return 0;
}

/* The end of a calibration: what is stored now (the old record unless the new one was
 * written and reads back valid), and the EVENT. */
static void done(uint8_t result, uint16_t detail)
{
    phase = PH_IDLE;
    load();
    if (result == PROTO_LEVEL_RES_STORED && status != PROTO_LEVEL_STORED && !ground_mode) {
        result = PROTO_LEVEL_RES_WRITE_FAILED;
    }
    tx_event(PROTO_EV_LEVEL_DONE, result, detail);
}

/* Sampling is over: each limb's rest tilt, checked, then the write. */
static void measured(void)
{
    uint8_t i, far = 0;
    int16_t o[CFG_N_LIMBS];
    uint16_t crc;
    for (i = 0; i < CFG_N_LIMBS; i++) {
        o[i] = (int16_t)(ground[i] + (int16_t)(sum[i] / LEVEL_SAMPLES)); /* a shift */
        if (!ground_mode) {
            o[i] = (int16_t)(o[i] + level_offset_cdeg(i));
        }
        if (o[i] > LEVEL_MAX_CDEG || o[i] < -LEVEL_MAX_CDEG) {
            far |= (uint8_t)(1u << i);
        }
    }
    if (far) {
        done(PROTO_LEVEL_RES_TOO_TILTED, far);
        return;
    }
    for (i = 0; i < CFG_N_LIMBS; i++) {
        if (ground_mode) {
            ground[i] = o[i];
        } else {
            ground[i] = 0;
            rec[2u + 2u * i] = (uint8_t)o[i];
            rec[3u + 2u * i] = (uint8_t)((uint16_t)o[i] >> 8);
        }
    }
    if (ground_mode) {
        done(PROTO_LEVEL_RES_STORED, 0); /* applied (not stored: this ground only) */
        return;
    }
    rec[0] = LEVEL_MAGIC;
    rec[1] = CFG_N_LIMBS;
    crc = rec_crc();
    rec[CRC_AT] = (uint8_t)crc;
    rec[CRC_AT + 1u] = (uint8_t)(crc >> 8);
    write(LEVEL_RECORD_BYTES);
    if (phase != PH_WRITING) {
        done(PROTO_LEVEL_RES_WRITE_FAILED, 0);
    }
}

void level_poll(void)
{
    uint8_t i, dead = imucheck_bad();
    int8_t r;
    if (phase == PH_SAMPLING) {
        for (i = 0; i < CFG_N_LIMBS; i++) {
            if (psi_level(i) == PSI_UNKNOWN) {
                dead |= (uint8_t)(1u << i); /* starting up: wait for it, a while */
            }
        }
        if (imucheck_bad() || (dead && ++waited > LEVEL_WAIT_TICKS)) {
            done(PROTO_LEVEL_RES_IMU, dead);
        } else if (seq_running() || fault_latched()) {
            done(PROTO_LEVEL_RES_INTERRUPTED, 0);
        } else if (!dead) {
            for (i = 0; i < CFG_N_LIMBS; i++) {
                sum[i] += psi_last_centideg(i);
            }
            if (--left == 0u) {
                measured();
            }
        }
    } else if (phase == PH_WRITING) {
        r = hal_nv_poll();
        if (r == HAL_NV_BUSY) {
            return;
        }
        if (clearing) {
            phase = PH_IDLE;
            load();
        } else {
            done(r == 0 ? PROTO_LEVEL_RES_STORED : PROTO_LEVEL_RES_WRITE_FAILED, 0);
        }
    }
}

uint8_t level_status(void)
{
    return phase != PH_IDLE && !clearing ? PROTO_LEVEL_CALIBRATING : status;
}
