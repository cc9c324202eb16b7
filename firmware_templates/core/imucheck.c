/* imucheck.c - see imucheck.h. */
#include "imucheck.h"

#include <string.h>

#include "fault.h"
#include "hal.h"
#include "imubus.h"
#include "initzero.h"
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
/* A state number is below CFG_N_STATES ≤ 65535 (proleg build refuses more): never UNKNOWN. */
typedef char unknown_is_no_state[CFG_N_STATES <= IMUCHECK_UNKNOWN ? 1 : -1];

/* Identical samples in a row: a byte where the limit fits one (it never counts past the limit:
 * reaching it marks the limb bad, and its restart clears the count). */
#if CFG_IMU_STUCK_SAMPLES <= 0xFFu
typedef uint8_t stuck_count_t;
#else
typedef uint16_t stuck_count_t;
#endif

/* Per limb, in one record: on an 8-bit MCU a function then computes the limb's address once. */
typedef struct {
    uint8_t rx[MPU6050_ACCEL_BYTES]; /* the transaction's reply */
    uint8_t res;                     /* RES_*: what the limb's last transaction gave */
    uint8_t phase;                   /* start-up step, PHASE_RUN: reading */
    uint32_t t0;                     /* hal_micros() at (re)start */
    uint32_t wait;                   /* µs after t0 before the first transaction */
    uint8_t err;                     /* failed reads in a row */
    stuck_count_t stuck;             /* identical samples in a row */
    mpu6050_accel_t last;
} limb_t;

static struct {
    uint8_t bad; /* bit per limb: IMU faulted, not read until CLEAR(FAULTS) */
    uint16_t measured; /* debounced robot state, IMUCHECK_UNKNOWN until every limb has one */
    /* One transaction at a time in the background, limbs taken in turn. A limb is begun
     * again only once the tick has taken its last result, so a result is never overwritten
     * or dropped, and each IMU is read once a tick while the bus has the time. */
    uint8_t cur; /* limb whose transaction is in flight, or NO_LIMB */
    uint8_t turn; /* the limb to try first when the bus is free */
    uint8_t tx[2];
    limb_t limb[CFG_N_LIMBS];
} st;

/* Limb `limb` is marked bad (its bit in st.bad). One copy of the variable shift (issue 11). */
#if defined(__GNUC__)
__attribute__((noinline))
#endif
static uint8_t is_bad(uint8_t limb)
{
    return (uint8_t)((st.bad >> limb) & 1u);
}

static void imu_fault(uint8_t limb, uint8_t code)
{
    st.bad = (uint8_t)(st.bad | (1u << limb));
    fault_raise(code, limb);
}

void imucheck_init(void)
{
    INIT_ZERO(st);
    st.measured = IMUCHECK_UNKNOWN;
    st.cur = NO_LIMB;
    imubus_init();
}

#if defined(__GNUC__)
__attribute__((noinline)) /* smaller out of line (measured, issue 11) */
#endif
static void restart(uint8_t limb, uint32_t wait_us)
{
    limb_t *l = &st.limb[limb];
    memset(l, 0, sizeof *l); /* no result, start-up step 0, no errors */
    l->t0 = hal_micros();
    l->wait = wait_us;
}

#if defined(__GNUC__)
__attribute__((noinline)) /* smaller out of line (measured, issue 11) */
#endif
void imucheck_power_up(uint8_t limb)
{
    restart(limb, START_FIRST_US);
}

#if defined(__GNUC__)
__attribute__((noinline)) /* smaller out of line (measured, issue 11) */
#endif
void imucheck_start(uint8_t limb)
{
    restart(limb, 0);
}

/* µs since limb l's (re)start (wrap-safe). One out-of-line copy for begin and
 * past_deadline. */
#if defined(__GNUC__)
__attribute__((noinline))
#endif
static uint32_t since_start(const limb_t *l)
{
    return (uint32_t)(hal_micros() - l->t0);
}

/* Begin the transaction of `limb` (its start-up step or its accelerometer read);
 * 0 if begun. A limb whose last result is not taken yet, that is bad or still in its
 * power-up wait has none. */
static int8_t begin(uint8_t limb)
{
    limb_t *l = &st.limb[limb];
    uint8_t ntx, nrx;
    if (l->res != RES_NONE || is_bad(limb) || since_start(l) < l->wait) {
        return -1;
    }
    if (l->phase < PHASE_RUN) {
        mpu6050_init_step(l->phase, st.tx, &ntx, &nrx);
    } else {
        st.tx[0] = MPU6050_REG_ACCEL_XOUT_H;
        ntx = 1;
        nrx = MPU6050_ACCEL_BYTES;
    }
    /* Behind a multiplexer its control byte goes first, in the background too (imubus.h). */
    return imubus_begin(limb, ROM_U8(&imu_addr[limb]), st.tx, ntx, l->rx, nrx) == 0 ? 0 : -1;
}

void imucheck_service(void)
{
    int8_t r;
    uint8_t k, t, i = st.cur;
    for (;;) {
        if (i != NO_LIMB) {
            r = imubus_poll();
            if (r == HAL_I2C_BUSY) {
                return;
            }
            st.limb[i].res = r == 0 ? RES_OK : RES_ERR;
        }
        /* the next limb in turn that can be begun; none: the bus rests until the tick */
        i = NO_LIMB;
        for (k = 0; k < CFG_N_LIMBS; k++) {
            t = st.turn;
            if (++st.turn == CFG_N_LIMBS) {
                st.turn = 0;
            }
            if (begin(t) == 0) {
                i = t;
                break;
            }
        }
        st.cur = i;
        if (i == NO_LIMB) {
            return;
        }
    }
}

/* The start-up deadline of limb i has passed. */
static uint8_t past_deadline(uint8_t i)
{
    const limb_t *l = &st.limb[i];
    return since_start(l) >= l->wait + START_DEADLINE_US;
}

/* A start-up step finished (or, RES_NONE, is still to be done): next step, a retry, or
 * (past the deadline) a fault. */
static void start_up(uint8_t i, uint8_t res)
{
    limb_t *l = &st.limb[i];
    int8_t r = MPU6050_ERR_BUS;
    if (res == RES_OK) {
        r = mpu6050_init_check(l->phase, l->rx[0]);
        if (r == MPU6050_OK) {
            l->phase++;
            return;
        }
    }
    if (res != RES_NONE) {
        l->phase = 0; /* from WHO_AM_I again */
    }
    if (past_deadline(i)) { /* no answer, a wrong one, or the bus never let it through */
        imu_fault(i, r == MPU6050_ERR_BUS ? PROTO_FAULT_IMU_NO_ACK : PROTO_FAULT_IMU_BAD_DATA);
    }
}

/* v² (< 2^30 + 1). One out-of-line copy: three 16×16→32 products inline cost more (issue 11). */
#if defined(__GNUC__)
__attribute__((noinline))
#endif
static uint32_t square(int16_t v)
{
    return (uint32_t)((int32_t)v * v);
}

/* A good accelerometer sample of limb i: checks, then the ψ classifier. 0 if usable. */
static int8_t sample(uint8_t i)
{
    limb_t *l = &st.limb[i];
    mpu6050_accel_t a;
    uint32_t g2;
    l->err = 0;
    mpu6050_accel(l->rx, &a);
    if (a.ax == l->last.ax && a.ay == l->last.ay && a.az == l->last.az) {
        if (++l->stuck >= CFG_IMU_STUCK_SAMPLES) {
            imu_fault(i, PROTO_FAULT_IMU_BAD_DATA);
            return -1;
        }
    } else {
        l->stuck = 0;
    }
    l->last = a;
    g2 = square(a.ax) + square(a.ay) + square(a.az);
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
        limb_t *l = &st.limb[i];
        res = l->res; /* RES_NONE while on the bus: it counts next tick */
        l->res = RES_NONE;
        if (is_bad(i)) {
            known = 0;
            continue;
        }
        if (l->phase < PHASE_RUN) {
            start_up(i, res);
            known = 0;
            continue;
        }
        if (res == RES_ERR) {
            if (++l->err >= 2u) {
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
    st.measured = known ? (uint16_t)seq_state_index(levels) : IMUCHECK_UNKNOWN;
}

uint16_t imucheck_measured(void)
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
