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

static int8_t i2c_result = -1;

/* The transaction completes at once (fake time does not pass inside a call). */
int8_t hal_i2c_begin(uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
#ifdef FAKE_HAL_SIM_MPU
    i2c_result = sim_mpu_transfer(addr7, tx, ntx, rx, nrx, fake_now_us) == 0 ? 0 : -1;
#else
    (void)addr7;
    (void)tx;
    (void)ntx;
    (void)rx;
    (void)nrx;
    i2c_result = -1;
#endif
    return 0;
}

int8_t hal_i2c_poll(void)
{
    return i2c_result;
}

uint8_t hal_reset_cause(void)
{
    return HAL_RESET_POWER_ON;
}

void hal_watchdog_feed(void)
{
}

void hal_tick_mark(uint8_t busy)
{
    (void)busy;
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
