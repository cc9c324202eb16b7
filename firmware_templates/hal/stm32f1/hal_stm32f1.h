/* hal_stm32f1.h - what the stm32f1 HAL's files share with each other (not part of hal.h).
 *
 * The HAL is split by peripheral: hal_stm32f1.c (bring-up: clock, SysTick time, IWDG,
 * reset cause, tick marker, hal_init, GPIO modes), pwm_stm32f1.c (TIM2-TIM4 PWM),
 * i2c_stm32f1.c (I2C1/I2C2, background transactions), uart_stm32f1.c (USART1) and
 * nv_stm32f1.c (the flash page behind hal_nv_*). Each part's init is called by hal_init.
 */
#ifndef PROLEG_HAL_STM32F1_H
#define PROLEG_HAL_STM32F1_H

#include <stdint.h>

#include "stm32f1_regs.h"

/* Registers for the issue 11 fixes, not (yet) in stm32f1_regs.h (RM0008, PM0056). */
#define SCB_ICSR REG32(0xE000ED04u)
#define SCB_ICSR_PENDSTSET (1u << 26) /* SysTick pending: cleared when it is taken, not on read */
#define RCC_CSR REG32(RCC_BASE + 0x24u)
#define RCC_CSR_RMVF (1u << 24)
#define RCC_CSR_IWDGRSTF (1u << 29)
#define RCC_CSR_SFTRSTF (1u << 28)
#define RCC_CSR_PORRSTF (1u << 27)
#define RCC_CSR_PINRSTF (1u << 26)
#define IWDG_KR REG32(0x40003000u)
#define IWDG_PR REG32(0x40003004u)
#define IWDG_RLR REG32(0x40003008u)
#define BKP_DR1 REG32(0x40006C04u) /* RM0008 §5.4.1; BKP clock off: writes are ignored */
#define GPIO_IDR(b) REG32((b) + 0x08u)
#define GPIO_BRR(b) REG32((b) + 0x14u)
#define GPIO_OUT_OD_50MHZ 0x7u

/* The system clock in Hz: 72 MHz from the PLL, or 8 MHz (HSI) without a crystal. */
extern uint32_t sysclk;

/* Pin `pin` of port 0 = GPIOA, 1 = GPIOB to a CRL/CRH mode (stm32f1_regs.h GPIO_*). */
void gpio_mode(uint8_t port, uint8_t pin, uint32_t mode);

/* Each part's set-up, called by hal_init after the clock is up. */
void pwm_init(void);
void i2c_setup(uint8_t bus); /* also on first use of bus 1, and after a bus recovery */
void usart1_init(void);

#endif /* PROLEG_HAL_STM32F1_H */
