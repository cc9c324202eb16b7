/* hal_stm32f1.c - hal.h for the STM32F103 ("Blue Pill"), bare-metal registers: the
 * bring-up (clock, SysTick time, IWDG, reset cause, the tick marker, hal_init) and GPIO.
 * The peripherals are in their own files (hal_stm32f1.h lists them).
 *
 * Clock: 8 MHz HSE × 9 = 72 MHz (APB1 36 MHz, APB2 72 MHz); if the crystal does not
 * start, the board runs on the 8 MHz HSI and every divider follows `sysclk`.
 * SysTick: 1 ms interrupt; hal_micros = ms·1000 + elapsed counts (the core paces the
 * control tick on it). PWM: TIM2/TIM3/TIM4 channels from the board pin map (CFG_PWM_MAP:
 * {timer, channel, port 0=A 1=B, pin}), 1000 counts per period at CFG_PWM_HZ.
 * I2C1 on PB6/PB7 (and I2C2 on PB10/PB11) at CFG_I2C_HZ (fast mode): one background
 * transaction at a time, moved on by hal_i2c_poll (a state machine on the status flags).
 * USART1 on PA9/PA10 at CFG_UART_BAUD; its interrupt moves bytes to and from the core's
 * rings (uart.h). main() is the core's.
 */
#include <stdint.h>

#include "hal.h"
#include "hal_stm32f1.h"
#include "robot_config.h"

uint32_t sysclk = 8000000u;
static volatile uint32_t ms_count;
static uint32_t systick_load; /* SYST_RVR + 1, set with it in hal_init: one register read less per hal_micros */
static uint8_t reset_cause;

void SysTick_Handler(void);

/* ------------------------------------------------------------------ clock and time */

static int8_t wait_bit(volatile uint32_t *reg, uint32_t mask, uint32_t spins)
{
    while (!(*reg & mask)) {
        if (spins-- == 0u) {
            return -1;
        }
    }
    return 0;
}

static void clock_init(void)
{
    RCC_CR |= RCC_CR_HSEON;
    if (wait_bit(&RCC_CR, RCC_CR_HSERDY, 200000u) != 0) {
        return; /* no crystal: stay on HSI 8 MHz */
    }
    FLASH_ACR = 0x12u;                                  /* prefetch on, 2 wait states */
    RCC_CFGR = (7u << 18) | (1u << 16) | (4u << 8);     /* PLL ×9 from HSE, APB1 /2 */
    RCC_CR |= RCC_CR_PLLON;
    if (wait_bit(&RCC_CR, RCC_CR_PLLRDY, 200000u) != 0) {
        return;
    }
    RCC_CFGR = (RCC_CFGR & ~3u) | 2u;                   /* system clock = PLL */
    while ((RCC_CFGR & (3u << 2)) != (2u << 2)) {
    }
    sysclk = 72000000u;
}

void SysTick_Handler(void)
{
    ms_count++;
}

uint32_t hal_micros(void)
{
    uint32_t m0, ms, val;
    uint32_t load = systick_load;
    /* Not COUNTFLAG: it is clear-on-read and the SysTick handler never reads it, so it
     * stayed set after the handler ran and the next call counted that ms twice. */
    do {
        m0 = ms_count;
        ms = m0;
        val = SYST_CVR;
        if (SCB_ICSR & SCB_ICSR_PENDSTSET) { /* wrapped, interrupt not yet taken */
            val = SYST_CVR;                  /* a count after the wrap */
            ms = m0 + 1u;
        }
    } while (m0 != ms_count);
    /* The count 0 is where the next millisecond starts (the wrap is flagged on reaching it). */
    return ms * 1000u + (val ? load - val : 0u) / (sysclk / 1000000u);
}

/* ------------------------------------------------------------------ GPIO */

static uint32_t port_base(uint8_t port)
{
    return port ? GPIOB_BASE : GPIOA_BASE;
}

void gpio_mode(uint8_t port, uint8_t pin, uint32_t mode)
{
    uint32_t base = port_base(port);
    volatile uint32_t *cr = pin < 8u ? &GPIO_CRL(base) : &GPIO_CRH(base);
    uint32_t shift = 4u * (pin & 7u);
    *cr = (*cr & ~(0xFu << shift)) | (mode << shift);
}

/* ------------------------------------------------------------------ watchdog, reset cause */

/* IWDG on the LSI (40 kHz typical, 30-60 kHz: DS5319 table 24): prescaler /8, reload 249:
 * 50 ms typical (33-67 ms). Once started only a reset stops it. */
static void iwdg_start(void)
{
    IWDG_KR = 0x5555u;
    IWDG_PR = 1u;
    IWDG_RLR = 249u;
    IWDG_KR = 0xAAAAu;
    IWDG_KR = 0xCCCCu;
}

void hal_watchdog_feed(void)
{
    IWDG_KR = 0xAAAAu;
}

/* RCC_CSR's flags survive a reset until RMVF clears them: read once at boot, then clear. */
static void reset_cause_read(void)
{
    uint32_t csr = RCC_CSR;
    if (csr & RCC_CSR_IWDGRSTF) {
        reset_cause = HAL_RESET_WATCHDOG;
    } else if (csr & RCC_CSR_SFTRSTF) {
        reset_cause = HAL_RESET_SOFTWARE;
    } else if (csr & RCC_CSR_PORRSTF) {
        reset_cause = HAL_RESET_POWER_ON;
    } else if (csr & RCC_CSR_PINRSTF) {
        reset_cause = HAL_RESET_EXTERNAL;
    } else {
        reset_cause = HAL_RESET_UNKNOWN;
    }
    RCC_CSR |= RCC_CSR_RMVF;
}

uint8_t hal_reset_cause(void)
{
    return reset_cause;
}

/* The tick-budget marker: a store to BKP_DR1 with the BKP clock off, which the chip
 * ignores and the arm-emu board times (docs/emulators-arm.md). */
void hal_tick_mark(uint8_t busy)
{
    BKP_DR1 = busy;
}

/* ------------------------------------------------------------------ bring-up */

void hal_init(void)
{
    uint32_t load;
    reset_cause_read(); /* first: RMVF clears the flags for the next reset */
    clock_init();
    RCC_APB2ENR |= RCC_APB2_AFIO | RCC_APB2_IOPA | RCC_APB2_IOPB | RCC_APB2_USART1;
    load = sysclk / 1000u; /* once: a register store in between would make the compiler read sysclk again */
    SYST_RVR = load - 1u;
    systick_load = load;
    SYST_CVR = 0;
    SYST_CSR = 7u; /* processor clock, interrupt, enable */
    pwm_init();
    i2c_setup(0); /* I2C1: PB6 = SCL, PB7 = SDA, alternate open-drain */
    usart1_init();
    iwdg_start(); /* fed by the core's main loop once per completed tick */
}
