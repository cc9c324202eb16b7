/* uart_stm32f1.c - the host link on the STM32F103's USART1 (PA9 = TX, PA10 = RX) at
 * CFG_UART_BAUD, 8N1: its interrupt moves bytes to and from the core's rings (uart.h).
 * Part of the stm32f1 HAL (hal_stm32f1.h).
 */
#include <stdint.h>

#include "hal.h"
#include "hal_stm32f1.h"
#include "robot_config.h"
#include "uart.h"

void USART1_IRQHandler(void);

void usart1_init(void)
{
    /* USART1: PA9 = TX (AF push-pull), PA10 = RX (input, pull-up). */
    gpio_mode(0, 9, GPIO_AF_PP_50MHZ);
    gpio_mode(0, 10, GPIO_IN_PULL);
    GPIO_BSRR(GPIOA_BASE) = 1u << 10;
    USART_BRR = (sysclk + CFG_UART_BAUD / 2u) / CFG_UART_BAUD; /* APB2 = sysclk */
    USART_CR1 = USART_CR1_UE | USART_CR1_TE | USART_CR1_RE | USART_CR1_RXNEIE;
    NVIC_ISER(USART1_IRQN / 32u) = 1u << (USART1_IRQN % 32u);
}

void USART1_IRQHandler(void)
{
    uint32_t sr = USART_SR;
    if (sr & (USART_SR_RXNE | USART_SR_ORE)) {
        (void)uart_isr_rx((uint8_t)USART_DR);
    }
    if ((sr & USART_SR_TXE) && (USART_CR1 & USART_CR1_TXEIE)) {
        int b = uart_isr_tx();
        if (b < 0) {
            USART_CR1 &= ~USART_CR1_TXEIE;
        } else {
            USART_DR = (uint32_t)b;
        }
    }
}

void hal_uart_tx_start(void)
{
    USART_CR1 |= USART_CR1_TXEIE;
}
