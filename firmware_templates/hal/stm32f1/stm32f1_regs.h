/* stm32f1_regs.h - the few STM32F103 registers hal_stm32f1.c uses (RM0008), by address.
 * No vendor headers: a register is REG32(base + offset). */
#ifndef PROLEG_STM32F1_REGS_H
#define PROLEG_STM32F1_REGS_H

#include <stdint.h>

#define REG32(addr) (*(volatile uint32_t *)(uintptr_t)(addr))

#define RCC_BASE 0x40021000u
#define RCC_CR REG32(RCC_BASE + 0x00u)
#define RCC_CFGR REG32(RCC_BASE + 0x04u)
#define RCC_APB2ENR REG32(RCC_BASE + 0x18u)
#define RCC_APB1ENR REG32(RCC_BASE + 0x1Cu)
#define RCC_CR_HSEON (1u << 16)
#define RCC_CR_HSERDY (1u << 17)
#define RCC_CR_PLLON (1u << 24)
#define RCC_CR_PLLRDY (1u << 25)
#define RCC_APB2_AFIO (1u << 0)
#define RCC_APB2_IOPA (1u << 2)
#define RCC_APB2_IOPB (1u << 3)
#define RCC_APB2_USART1 (1u << 14)
#define RCC_APB1_TIM2 (1u << 0)
#define RCC_APB1_TIM3 (1u << 1)
#define RCC_APB1_TIM4 (1u << 2)
#define RCC_APB1_I2C1 (1u << 21)

#define FLASH_ACR REG32(0x40022000u)

#define GPIOA_BASE 0x40010800u
#define GPIOB_BASE 0x40010C00u
#define GPIO_CRL(b) REG32((b) + 0x00u)
#define GPIO_CRH(b) REG32((b) + 0x04u)
#define GPIO_ODR(b) REG32((b) + 0x0Cu)
#define GPIO_BSRR(b) REG32((b) + 0x10u)
#define GPIO_AF_PP_50MHZ 0xBu
#define GPIO_AF_OD_50MHZ 0xFu
#define GPIO_IN_PULL 0x8u

#define TIM2_BASE 0x40000000u
#define TIM3_BASE 0x40000400u
#define TIM4_BASE 0x40000800u
#define TIM_CR1(b) REG32((b) + 0x00u)
#define TIM_EGR(b) REG32((b) + 0x14u)
#define TIM_CCMR1(b) REG32((b) + 0x18u)
#define TIM_CCMR2(b) REG32((b) + 0x1Cu)
#define TIM_CCER(b) REG32((b) + 0x20u)
#define TIM_PSC(b) REG32((b) + 0x28u)
#define TIM_ARR(b) REG32((b) + 0x2Cu)
#define TIM_CCR(b, ch) REG32((b) + 0x34u + 4u * ((ch) - 1u))

#define I2C1_BASE 0x40005400u
#define I2C_CR1 REG32(I2C1_BASE + 0x00u)
#define I2C_CR2 REG32(I2C1_BASE + 0x04u)
#define I2C_DR REG32(I2C1_BASE + 0x10u)
#define I2C_SR1 REG32(I2C1_BASE + 0x14u)
#define I2C_SR2 REG32(I2C1_BASE + 0x18u)
#define I2C_CCR REG32(I2C1_BASE + 0x1Cu)
#define I2C_TRISE REG32(I2C1_BASE + 0x20u)
#define I2C_CR1_PE (1u << 0)
#define I2C_CR1_START (1u << 8)
#define I2C_CR1_STOP (1u << 9)
#define I2C_CR1_ACK (1u << 10)
#define I2C_CR1_SWRST (1u << 15)
#define I2C_SR1_SB (1u << 0)
#define I2C_SR1_ADDR (1u << 1)
#define I2C_SR1_BTF (1u << 2)
#define I2C_SR1_RXNE (1u << 6)
#define I2C_SR1_TXE (1u << 7)
#define I2C_SR1_BERR (1u << 8)
#define I2C_SR1_ARLO (1u << 9)
#define I2C_SR1_AF (1u << 10)
#define I2C_SR2_BUSY (1u << 1)

#define USART1_BASE 0x40013800u
#define USART_SR REG32(USART1_BASE + 0x00u)
#define USART_DR REG32(USART1_BASE + 0x04u)
#define USART_BRR REG32(USART1_BASE + 0x08u)
#define USART_CR1 REG32(USART1_BASE + 0x0Cu)
#define USART_SR_ORE (1u << 3)
#define USART_SR_RXNE (1u << 5)
#define USART_SR_TXE (1u << 7)
#define USART_CR1_RE (1u << 2)
#define USART_CR1_TE (1u << 3)
#define USART_CR1_RXNEIE (1u << 5)
#define USART_CR1_TXEIE (1u << 7)
#define USART_CR1_UE (1u << 13)
#define USART1_IRQN 37u

#define SYST_CSR REG32(0xE000E010u)
#define SYST_RVR REG32(0xE000E014u)
#define SYST_CVR REG32(0xE000E018u)
#define NVIC_ISER(n) REG32(0xE000E100u + 4u * (n))

#endif /* PROLEG_STM32F1_REGS_H */
