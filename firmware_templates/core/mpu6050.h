/* mpu6050.h - the few MPU-6050 registers proleg uses, and its start-up as a list of
 * single I2C transactions (hal_i2c_begin/hal_i2c_poll), so nothing here waits on the bus.
 *
 * Contract. The start-up is MPU6050_INIT_STEPS transactions, done one by one in order:
 * mpu6050_init_step(i, tx, &ntx, &nrx) fills the bytes to write for step i and says how
 * many to read; mpu6050_init_check(i, rx) says whether step i's answer is right:
 * WHO_AM_I is 0x68 whatever AD0 is (MPU6050_ERR_IDENTITY otherwise); then wake from the
 * power-up sleep (PWR_MGMT_1 = PLL on gyro X), sample divider, digital low-pass filter,
 * accelerometer and gyro full scale; then ACCEL_CONFIG and PWR_MGMT_1 read back
 * (MPU6050_ERR_CONFIG if a setting did not stick). The accelerometer is read as the six
 * bytes 0x3B..0x40 (big-endian) in one transaction: mpu6050_accel() decodes them.
 * Start-up time: the register interface answers 20 ms (typ.) to 100 ms (max.) after
 * power-up (MPU-6000/6050 Product Specification rev. 3.4, table 6.3, "Start-Up Time for
 * Register Read/Write").
 */
#ifndef PROLEG_MPU6050_H
#define PROLEG_MPU6050_H

#include <stdint.h>

#define MPU6050_ADDR_LOW 0x68u
#define MPU6050_ADDR_HIGH 0x69u
#define MPU6050_REG_SMPLRT_DIV 0x19u
#define MPU6050_REG_CONFIG 0x1Au
#define MPU6050_REG_GYRO_CONFIG 0x1Bu
#define MPU6050_REG_ACCEL_CONFIG 0x1Cu
#define MPU6050_REG_ACCEL_XOUT_H 0x3Bu
#define MPU6050_REG_TEMP_OUT_H 0x41u
#define MPU6050_REG_GYRO_XOUT_H 0x43u
#define MPU6050_REG_PWR_MGMT_1 0x6Bu
#define MPU6050_REG_WHO_AM_I 0x75u
#define MPU6050_WHO_AM_I_VALUE 0x68u
#define MPU6050_PWR_DEVICE_RESET 0x80u
#define MPU6050_PWR_SLEEP 0x40u
#define MPU6050_PWR_CLK_PLL_GX 0x01u

/* Settings used by proleg: DLPF 3 (accel 44 Hz), 1 kHz sampling, ±4 g, ±500 °/s. */
#define MPU6050_DLPF_CFG 3u
#define MPU6050_AFS_SEL 1u
#define MPU6050_FS_SEL 1u
#define MPU6050_ACCEL_LSB_PER_G 8192

/* Start-up time (see above), µs. */
#define MPU6050_STARTUP_TYP_US 20000UL
#define MPU6050_STARTUP_MAX_US 100000UL

#define MPU6050_OK 0
#define MPU6050_ERR_BUS (-1)      /* no ACK, bus error, timeout */
#define MPU6050_ERR_IDENTITY (-2) /* WHO_AM_I is not 0x68 */
#define MPU6050_ERR_CONFIG (-3)   /* a setting did not read back */

#define MPU6050_INIT_STEPS 8u
#define MPU6050_ACCEL_BYTES 6u

typedef struct {
    int16_t ax, ay, az;
} mpu6050_accel_t;

void mpu6050_init_step(uint8_t step, uint8_t tx[2], uint8_t *ntx, uint8_t *nrx);
int8_t mpu6050_init_check(uint8_t step, uint8_t rx);
void mpu6050_accel(const uint8_t b[MPU6050_ACCEL_BYTES], mpu6050_accel_t *out);

#endif /* PROLEG_MPU6050_H */
