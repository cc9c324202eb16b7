/* fake_hal.c - see fake_hal.h. */
#include "fake_hal.h"

#include <string.h>

#ifdef FAKE_HAL_SIM_MPU
#include "sim_mpu6050.h"
#endif

uint16_t fake_pwm[FAKE_PWM_MAX];
uint32_t fake_pwm_writes;
uint64_t fake_now_us;

void fake_hal_reset(void)
{
    memset(fake_pwm, 0xAA, sizeof fake_pwm); /* "unknown": a test sees what was never written */
    fake_pwm_writes = 0;
    fake_now_us = 0;
}

void hal_init(void)
{
}

uint32_t hal_micros(void)
{
    return (uint32_t)fake_now_us;
}

int hal_i2c_write_read(uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
#ifdef FAKE_HAL_SIM_MPU
    return sim_mpu_transfer(addr7, tx, ntx, rx, nrx, fake_now_us);
#else
    (void)addr7;
    (void)tx;
    (void)ntx;
    (void)rx;
    (void)nrx;
    return -1;
#endif
}

void hal_pwm_set(uint8_t channel, uint16_t duty_permyriad)
{
    if (channel < FAKE_PWM_MAX) {
        fake_pwm[channel] = duty_permyriad;
    }
    fake_pwm_writes++;
}

void hal_uart_tx_start(void)
{
}
