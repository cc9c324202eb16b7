/* mpu6050.c - see mpu6050.h. */
#include "mpu6050.h"

#include "imubus.h"

static int8_t write_reg(uint8_t addr, uint8_t reg, uint8_t value)
{
    uint8_t tx[2];
    tx[0] = reg;
    tx[1] = value;
    return imubus_write_read(addr, tx, 2, (uint8_t *)0, 0) == 0 ? MPU6050_OK : MPU6050_ERR_BUS;
}

static int8_t read_regs(uint8_t addr, uint8_t reg, uint8_t *rx, uint8_t n)
{
    return imubus_write_read(addr, &reg, 1, rx, n) == 0 ? MPU6050_OK : MPU6050_ERR_BUS;
}

int8_t mpu6050_init(uint8_t addr)
{
    uint8_t v = 0;
    uint8_t accel_cfg = (uint8_t)(MPU6050_AFS_SEL << 3);
    if (read_regs(addr, MPU6050_REG_WHO_AM_I, &v, 1) != MPU6050_OK) {
        return MPU6050_ERR_BUS;
    }
    if (v != MPU6050_WHO_AM_I_VALUE) {
        return MPU6050_ERR_IDENTITY;
    }
    if (write_reg(addr, MPU6050_REG_PWR_MGMT_1, MPU6050_PWR_CLK_PLL_GX) != MPU6050_OK ||
        write_reg(addr, MPU6050_REG_SMPLRT_DIV, 0) != MPU6050_OK ||
        write_reg(addr, MPU6050_REG_CONFIG, MPU6050_DLPF_CFG) != MPU6050_OK ||
        write_reg(addr, MPU6050_REG_GYRO_CONFIG, (uint8_t)(MPU6050_FS_SEL << 3)) != MPU6050_OK ||
        write_reg(addr, MPU6050_REG_ACCEL_CONFIG, accel_cfg) != MPU6050_OK) {
        return MPU6050_ERR_BUS;
    }
    if (read_regs(addr, MPU6050_REG_ACCEL_CONFIG, &v, 1) != MPU6050_OK) {
        return MPU6050_ERR_BUS;
    }
    if ((v & 0x18u) != accel_cfg) {
        return MPU6050_ERR_CONFIG;
    }
    if (read_regs(addr, MPU6050_REG_PWR_MGMT_1, &v, 1) != MPU6050_OK) {
        return MPU6050_ERR_BUS;
    }
    return (v & MPU6050_PWR_SLEEP) ? MPU6050_ERR_CONFIG : MPU6050_OK;
}

int8_t mpu6050_read_accel(uint8_t addr, mpu6050_accel_t *out)
{
    uint8_t b[6];
    if (read_regs(addr, MPU6050_REG_ACCEL_XOUT_H, b, 6) != MPU6050_OK) {
        return MPU6050_ERR_BUS;
    }
    out->ax = (int16_t)(uint16_t)(((uint16_t)b[0] << 8) | b[1]);
    out->ay = (int16_t)(uint16_t)(((uint16_t)b[2] << 8) | b[3]);
    out->az = (int16_t)(uint16_t)(((uint16_t)b[4] << 8) | b[5]);
    return MPU6050_OK;
}
