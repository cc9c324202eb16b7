/* startup_stm32f1.c - vector table and reset handler for the STM32F103 (medium density).
 * Reset: copy .data from flash, zero .bss, call main(). Unused interrupts spin in
 * default_handler (a fault there is a bug: the watchdog of a real build would reset). */
#include <stdint.h>

extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _estack;
extern int main(void);

void reset_handler(void);
void default_handler(void);
void SysTick_Handler(void);
void USART1_IRQHandler(void);
/* bxCAN (can_stm32f1.c, only in images whose host link is CAN): weak, so other images keep
 * default_handler there. */
void USB_HP_CAN_TX_IRQHandler(void) __attribute__((weak, alias("default_handler")));
void USB_LP_CAN_RX0_IRQHandler(void) __attribute__((weak, alias("default_handler")));

void default_handler(void)
{
    for (;;) {
    }
}

void reset_handler(void)
{
    uint32_t *src = &_sidata;
    uint32_t *dst = &_sdata;
    while (dst < &_edata) {
        *dst++ = *src++;
    }
    for (dst = &_sbss; dst < &_ebss; dst++) {
        *dst = 0;
    }
    (void)main();
    for (;;) {
    }
}

typedef void (*vector_t)(void);

#define N_VECTORS (16u + 60u)
#define V(n) [n] = default_handler

/* Index = exception number; IRQ n is 16 + n. */
__attribute__((section(".isr_vector"), used)) const vector_t vector_table[N_VECTORS] = {
    [0] = (vector_t)(uintptr_t)&_estack,
    [1] = reset_handler,
    V(2), V(3), V(4), V(5), V(6), V(11), V(12), V(14),
    [15] = SysTick_Handler,
    V(16), V(17), V(18), V(19), V(20), V(21), V(22), V(23), V(24), V(25), V(26), V(27), V(28), V(29),
    V(30), V(31), V(32), V(33), V(34),
    [16 + 19] = USB_HP_CAN_TX_IRQHandler, [16 + 20] = USB_LP_CAN_RX0_IRQHandler, V(37), V(38), V(39), V(40), V(41), V(42), V(43),
    V(44), V(45), V(46), V(47), V(48), V(49), V(50), V(51), V(52),
    [16 + 37] = USART1_IRQHandler,
    V(54), V(55), V(56), V(57), V(58), V(59), V(60), V(61), V(62), V(63), V(64), V(65), V(66), V(67),
    V(68), V(69), V(70), V(71), V(72), V(73), V(74), V(75),
};
