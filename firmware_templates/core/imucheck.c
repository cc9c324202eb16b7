/* imucheck.c - see imucheck.h. */
#include "imucheck.h"

#include <string.h>

#include "fault.h"
#include "hal.h"
#include "imubus.h"
#include "level.h"
#include "mpu6050.h"
#include "proto.h"
#include "psi.h"
#include "rom.h"
#include "seq.h"

/* |g|² plausibility band, 0.5 g .. 1.5 g, in LSB². */
#define G2_MIN ((uint32_t)(MPU6050_ACCEL_LSB_PER_G / 2) * (uint32_t)(MPU6050_ACCEL_LSB_PER_G / 2))
#define G2_MAX ((uint32_t)(3 * MPU6050_ACCEL_LSB_PER_G / 2) * (uint32_t)(3 * MPU6050_ACCEL_LSB_PER_G / 2))

/* Start-up: the first WHO_AM_I after the IMU's typical start-up time, retried until its
 * maximum plus margin, then a fault (mpu6050.h). A restart (CLEAR(FAULTS)) does not wait. */
#define START_FIRST_US MPU6050_STARTUP_TYP_US
#define START_DEADLINE_US (MPU6050_STARTUP_MAX_US + 50000UL)

#define PHASE_RUN MPU6050_INIT_STEPS /* 0..INIT_STEPS-1: start-up step; then reading */
#define RES_NONE 0u
#define RES_OK 1u
#define RES_ERR 2u
#define NO_LIMB 0xFFu

static const uint8_t imu_addr[CFG_N_LIMBS] ROM = CFG_LIMB_IMU_ADDR;

static struct {
    uint8_t bad; /* bit per limb: IMU faulted, not read until CLEAR(FAULTS) */
    uint8_t err[CFG_N_LIMBS];
    uint16_t stuck[CFG_N_LIMBS];
    mpu6050_accel_t last[CFG_N_LIMBS];
    uint32_t measured; /* debounced robot state, IMUCHECK_UNKNOWN until every limb has one */
    /* start-up */
    uint8_t phase[CFG_N_LIMBS];
    int8_t why[CFG_N_LIMBS];    /* the last start-up failure (MPU6050_ERR_*) */
    uint32_t t0[CFG_N_LIMBS];   /* hal_micros() at (re)start */
    uint32_t wait[CFG_N_LIMBS]; /* µs after t0 before the first transaction */
    /* the transactions of this tick: one per limb, in limb order, in the background */
    uint8_t cur;                /* limb whose transaction is in flight, or NO_LIMB */
    uint8_t res[CFG_N_LIMBS];   /* RES_*: what that limb's last transaction gave */
    uint8_t tx[2];
    uint8_t rx[CFG_N_LIMBS][MPU6050_ACCEL_BYTES];
    uint8_t due; /* this period's transactions are still to begin */
} st;

static void imu_fault(uint8_t limb, uint8_t code)
{
    st.bad = (uint8_t)(st.bad | (1u << limb));
    fault_raise(code, limb);
}

void imucheck_init(void)
{
    memset(&st, 0, sizeof st);
    st.measured = IMUCHECK_UNKNOWN;
    st.cur = NO_LIMB;
    imubus_init();
}

static void restart(uint8_t limb, uint32_t wait_us)
{
    st.err[limb] = 0;
    st.stuck[limb] = 0;
    st.phase[limb] = 0;
    st.why[limb] = MPU6050_ERR_BUS;
    st.res[limb] = RES_NONE;
    st.t0[limb] = hal_micros();
    st.wait[limb] = wait_us;
}

void imucheck_power_up(uint8_t limb)
{
    restart(limb, START_FIRST_US);
}

void imucheck_start(uint8_t limb)
{
    restart(limb, 0);
}

/* Begin the transaction of `limb` (its start-up step or its accelerometer read);
 * 0 if begun. A limb that is bad or still in its power-up wait has none. */
static int8_t begin(uint8_t limb)
{
    uint8_t ntx, nrx;
    if ((st.bad & (1u << limb)) || (uint32_t)(hal_micros() - st.t0[limb]) < st.wait[limb]) {
        return -1;
    }
    if (st.phase[limb] < PHASE_RUN) {
        mpu6050_init_step(st.phase[limb], st.tx, &ntx, &nrx);
    } else {
        st.tx[0] = MPU6050_REG_ACCEL_XOUT_H;
        ntx = 1;
        nrx = MPU6050_ACCEL_BYTES;
    }
    /* Behind a multiplexer its control byte goes first, in the background too (imubus.h). */
    return imubus_begin(limb, ROM_U8(&imu_addr[limb]), st.tx, ntx, st.rx[limb], nrx) == 0 ? 0 : -1;
}

/* From `from` on, begin the next limb's transaction; NO_LIMB when none is left. */
static void next(uint8_t from)
{
    uint8_t i;
    for (i = from; i < CFG_N_LIMBS; i++) {
        if (begin(i) == 0) {
            st.cur = i;
            return;
        }
    }
    st.cur = NO_LIMB;
}

void imucheck_service(void)
{
    int8_t r;
    uint8_t limb;
    if (st.due && st.cur == NO_LIMB) {
        st.due = 0;
        next(0); /* between ticks: the samples are as fresh as the next tick can have them */
    }
    while (st.cur != NO_LIMB) {
        r = imubus_poll();
        if (r == HAL_I2C_BUSY) {
            return;
        }
        limb = st.cur;
        st.res[limb] = r == 0 ? RES_OK : RES_ERR;
        next((uint8_t)(limb + 1u));
    }
}

/* The start-up deadline of limb i has passed. */
static uint8_t past_deadline(uint8_t i)
{
    return (uint32_t)(hal_micros() - st.t0[i]) >= st.wait[i] + START_DEADLINE_US;
}

/* A start-up step finished: next step, a retry, or (past the deadline) a fault. */
static void start_up(uint8_t i, uint8_t res)
{
    int8_t r = res == RES_OK ? mpu6050_init_check(st.phase[i], st.rx[i][0]) : MPU6050_ERR_BUS;
    if (r == MPU6050_OK) {
        st.phase[i]++;
        return;
    }
    st.why[i] = r;
    st.phase[i] = 0; /* from WHO_AM_I again */
    if (past_deadline(i)) {
        imu_fault(i, r == MPU6050_ERR_BUS ? PROTO_FAULT_IMU_NO_ACK : PROTO_FAULT_IMU_BAD_DATA);
    }
}

/* A good accelerometer sample of limb i: checks, then the ψ classifier. 0 if usable. */
static int8_t sample(uint8_t i)
{
    mpu6050_accel_t a;
    uint32_t g2;
    st.err[i] = 0;
    mpu6050_accel(st.rx[i], &a);
    if (a.ax == st.last[i].ax && a.ay == st.last[i].ay && a.az == st.last[i].az) {
        if (++st.stuck[i] >= CFG_IMU_STUCK_SAMPLES) {
            imu_fault(i, PROTO_FAULT_IMU_BAD_DATA);
            return -1;
        }
    } else {
        st.stuck[i] = 0;
    }
    st.last[i] = a;
    g2 = (uint32_t)((int32_t)a.ax * a.ax) + (uint32_t)((int32_t)a.ay * a.ay) + (uint32_t)((int32_t)a.az * a.az);
    if (g2 < G2_MIN || g2 > G2_MAX) {
        imu_fault(i, PROTO_FAULT_IMU_BAD_DATA);
        return -1;
    }
    level_apply(i, &a.ax, &a.az); /* the stored rest tilt off (level.h) */
    psi_update(i, a.ax, a.az);
    return 0;
}

void imucheck_read(void)
{
    uint8_t levels[CFG_N_LIMBS];
    uint8_t i, res, known = 1;
    imucheck_service();
    for (i = 0; i < CFG_N_LIMBS; i++) {
        res = st.res[i];
        if (i == st.cur) {
            res = RES_NONE; /* still on the bus: its result counts next tick */
        }
        st.res[i] = RES_NONE;
        if (st.bad & (1u << i)) {
            known = 0;
            continue;
        }
        if (st.phase[i] < PHASE_RUN) {
            if (res != RES_NONE) {
                start_up(i, res);
            } else if (past_deadline(i)) {
                imu_fault(i, PROTO_FAULT_IMU_NO_ACK); /* the bus never let it through */
            }
            known = 0;
            continue;
        }
        if (res == RES_ERR) {
            if (++st.err[i] >= 2u) {
                imu_fault(i, PROTO_FAULT_IMU_NO_ACK);
                known = 0;
                continue;
            }
        } else if (res == RES_OK && sample(i) != 0) {
            known = 0;
            continue;
        }
        levels[i] = psi_level(i);
        if (levels[i] == PSI_UNKNOWN) {
            known = 0;
        }
    }
    st.measured = known ? (uint32_t)seq_state_index(levels) : IMUCHECK_UNKNOWN;
    st.due = 1;
}

uint32_t imucheck_measured(void)
{
    return st.measured;
}

uint8_t imucheck_bad(void)
{
    return st.bad;
}

uint8_t imucheck_take_bad(void)
{
    uint8_t bad = st.bad;
    st.bad = 0;
    return bad;
}
