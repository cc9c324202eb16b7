/* fake_hal.h - a recording hal.h for host unit tests: PWM duties per channel, a clock the
 * test sets, I2C answered by the simulated MPU-6050 models (sim_mpu6050.c) when linked
 * with FAKE_HAL_SIM_MPU, else by a test-provided function. */
#ifndef PROLEG_FAKE_HAL_H
#define PROLEG_FAKE_HAL_H

#include <stdint.h>

#include "hal.h"

#define FAKE_PWM_MAX 16
extern uint16_t fake_pwm[FAKE_PWM_MAX];
extern uint32_t fake_pwm_writes;
extern uint64_t fake_now_us;

void fake_hal_reset(void);

#endif
