/* imucheck.c - see imucheck.h. */
#include "imucheck.h"

#include <string.h>

#include "fault.h"
#include "imubus.h"
#include "mpu6050.h"
#include "proto.h"
#include "psi.h"
#include "rom.h"
#include "seq.h"

/* |g|² plausibility band, 0.5 g .. 1.5 g, in LSB². */
#define G2_MIN ((uint32_t)(MPU6050_ACCEL_LSB_PER_G / 2) * (uint32_t)(MPU6050_ACCEL_LSB_PER_G / 2))
#define G2_MAX ((uint32_t)(3 * MPU6050_ACCEL_LSB_PER_G / 2) * (uint32_t)(3 * MPU6050_ACCEL_LSB_PER_G / 2))

static const uint8_t imu_addr[CFG_N_LIMBS] ROM = CFG_LIMB_IMU_ADDR;

static struct {
    uint8_t bad; /* bit per limb: IMU faulted, not read until CLEAR(FAULTS) */
    uint8_t err[CFG_N_LIMBS];
    uint16_t stuck[CFG_N_LIMBS];
    mpu6050_accel_t last[CFG_N_LIMBS];
    uint32_t measured; /* debounced robot state, IMUCHECK_UNKNOWN until every limb has one */
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
    imubus_init();
}

void imucheck_start(uint8_t limb)
{
    int8_t r = imubus_select(limb) != 0 ? MPU6050_ERR_BUS : mpu6050_init(ROM_U8(&imu_addr[limb]));
    st.err[limb] = 0;
    st.stuck[limb] = 0;
    if (r == MPU6050_ERR_BUS) {
        imu_fault(limb, PROTO_FAULT_IMU_NO_ACK);
    } else if (r != MPU6050_OK) {
        imu_fault(limb, PROTO_FAULT_IMU_BAD_DATA);
    }
}

void imucheck_read(void)
{
    uint8_t levels[CFG_N_LIMBS];
    uint8_t i, known = 1;
    for (i = 0; i < CFG_N_LIMBS; i++) {
        mpu6050_accel_t a;
        uint32_t g2;
        if (st.bad & (1u << i)) {
            known = 0;
            continue;
        }
        if (imubus_select(i) != 0 || mpu6050_read_accel(ROM_U8(&imu_addr[i]), &a) != MPU6050_OK) {
            if (++st.err[i] >= 2u) {
                imu_fault(i, PROTO_FAULT_IMU_NO_ACK);
            }
        } else {
            st.err[i] = 0;
            if (a.ax == st.last[i].ax && a.ay == st.last[i].ay && a.az == st.last[i].az) {
                if (++st.stuck[i] >= CFG_IMU_STUCK_SAMPLES) {
                    imu_fault(i, PROTO_FAULT_IMU_BAD_DATA);
                    known = 0;
                    continue;
                }
            } else {
                st.stuck[i] = 0;
            }
            st.last[i] = a;
            g2 = (uint32_t)((int32_t)a.ax * a.ax) + (uint32_t)((int32_t)a.ay * a.ay) + (uint32_t)((int32_t)a.az * a.az);
            if (g2 < G2_MIN || g2 > G2_MAX) {
                imu_fault(i, PROTO_FAULT_IMU_BAD_DATA);
                known = 0;
                continue;
            }
            psi_update(i, a.ax, a.az);
        }
        levels[i] = psi_level(i);
        if (levels[i] == PSI_UNKNOWN) {
            known = 0;
        }
    }
    st.measured = known ? (uint32_t)seq_state_index(levels) : IMUCHECK_UNKNOWN;
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
