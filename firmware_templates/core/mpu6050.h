/* mpu6050.h - the few MPU-6050 registers proleg uses, over imubus_write_read (the bus imubus_select chose).
 *
 * Contract. mpu6050_init checks WHO_AM_I (0x68 whatever AD0 is), wakes the chip from
 * its power-up sleep (PWR_MGMT_1 = PLL on gyro X), sets the sample divider, the digital
 * low-pass filter and the accelerometer/gyro full scale, and reads ACCEL_CONFIG back.
 * mpu6050_read_accel reads the six accelerometer bytes 0x3B..0x40 (big-endian) in one
 * transaction: one I2C read per limb per tick.
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

#define MPU6050_OK 0
#define MPU6050_ERR_BUS (-1)      /* no ACK, bus error, timeout */
#define MPU6050_ERR_IDENTITY (-2) /* WHO_AM_I is not 0x68 */
#define MPU6050_ERR_CONFIG (-3)   /* a setting did not read back */

typedef struct {
    int16_t ax, ay, az;
} mpu6050_accel_t;

int8_t mpu6050_init(uint8_t addr);
int8_t mpu6050_read_accel(uint8_t addr, mpu6050_accel_t *out);

#endif /* PROLEG_MPU6050_H */
