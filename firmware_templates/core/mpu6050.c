/* mpu6050.c - see mpu6050.h. */
#include "mpu6050.h"

#include "rom.h"

#define ACCEL_CFG ((uint8_t)(MPU6050_AFS_SEL << 3))

/* {register, value to write} per step; a step with the value 0xFF reads the register. */
#define READ 0xFFu
static const uint8_t init_steps[MPU6050_INIT_STEPS][2] ROM = {
    {MPU6050_REG_WHO_AM_I, READ},
    {MPU6050_REG_PWR_MGMT_1, MPU6050_PWR_CLK_PLL_GX},
    {MPU6050_REG_SMPLRT_DIV, 0u},
    {MPU6050_REG_CONFIG, MPU6050_DLPF_CFG},
    {MPU6050_REG_GYRO_CONFIG, (uint8_t)(MPU6050_FS_SEL << 3)},
    {MPU6050_REG_ACCEL_CONFIG, ACCEL_CFG},
    {MPU6050_REG_ACCEL_CONFIG, READ},
    {MPU6050_REG_PWR_MGMT_1, READ},
};

void mpu6050_init_step(uint8_t step, uint8_t tx[2], uint8_t *ntx, uint8_t *nrx)
{
    uint8_t value = ROM_U8(&init_steps[step][1]);
    tx[0] = ROM_U8(&init_steps[step][0]);
    tx[1] = value;
    *ntx = value == READ ? 1u : 2u;
    *nrx = value == READ ? 1u : 0u;
}

int8_t mpu6050_init_check(uint8_t step, uint8_t rx)
{
    switch (step) {
    case 0:
        return rx == MPU6050_WHO_AM_I_VALUE ? MPU6050_OK : MPU6050_ERR_IDENTITY;
    case 6:
        return (rx & 0x18u) == ACCEL_CFG ? MPU6050_OK : MPU6050_ERR_CONFIG;
    case 7:
        return (rx & MPU6050_PWR_SLEEP) ? MPU6050_ERR_CONFIG : MPU6050_OK;
    default:
        return MPU6050_OK;
    }
}

void mpu6050_accel(const uint8_t b[MPU6050_ACCEL_BYTES], mpu6050_accel_t *out)
{
    out->ax = (int16_t)(uint16_t)(((uint16_t)b[0] << 8) | b[1]);
    out->ay = (int16_t)(uint16_t)(((uint16_t)b[2] << 8) | b[3]);
    out->az = (int16_t)(uint16_t)(((uint16_t)b[4] << 8) | b[5]);
}
