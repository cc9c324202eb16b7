/* hal_stm32f1.c - hal.h for the STM32F103 ("Blue Pill"), bare-metal registers.
 *
 * Clock: 8 MHz HSE × 9 = 72 MHz (APB1 36 MHz, APB2 72 MHz); if the crystal does not
 * start, the board runs on the 8 MHz HSI and every divider below follows `sysclk`.
 * SysTick: 1 ms interrupt; hal_micros = ms·1000 + elapsed counts (the core paces the
 * control tick on it). PWM: TIM2/TIM3/TIM4 channels from the board pin map (CFG_PWM_MAP:
 * {timer, channel, port 0=A 1=B, pin}), 1000 counts per period at CFG_PWM_HZ.
 * I2C1 on PB6/PB7 at CFG_I2C_HZ (fast mode), polled, every wait bounded by I2C_STEP_US.
 * USART1 on PA9/PA10 at CFG_UART_BAUD; its interrupt moves bytes to and from the core's
 * rings (uart.h). main() is the core's.
 */
#include <stdint.h>

#include "hal.h"
#include "robot_config.h"
#include "stm32f1_regs.h"
#include "uart.h"

#define I2C_STEP_US 300u
#define PWM_COUNTS 1000u

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


typedef struct {
    uint8_t timer;   /* 2, 3 or 4 */
    uint8_t channel; /* 1..4 */
    uint8_t port;    /* 0 = GPIOA, 1 = GPIOB */
    uint8_t pin;
} pwm_pin_t;

static const pwm_pin_t pwm_map[CFG_PWM_CHANNELS] = CFG_PWM_MAP;

static uint32_t sysclk = 8000000u;
static volatile uint32_t ms_count;
static uint8_t reset_cause;

void SysTick_Handler(void);
void USART1_IRQHandler(void);

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
    uint32_t load = SYST_RVR + 1u;
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

static void gpio_mode(uint8_t port, uint8_t pin, uint32_t mode)
{
    uint32_t base = port_base(port);
    volatile uint32_t *cr = pin < 8u ? &GPIO_CRL(base) : &GPIO_CRH(base);
    uint32_t shift = 4u * (pin & 7u);
    *cr = (*cr & ~(0xFu << shift)) | (mode << shift);
}

/* ------------------------------------------------------------------ PWM */

static uint32_t timer_base(uint8_t t)
{
    return t == 2u ? TIM2_BASE : t == 3u ? TIM3_BASE : TIM4_BASE;
}

static void pwm_init(void)
{
    uint8_t i;
    uint32_t psc = sysclk / (PWM_COUNTS * CFG_PWM_HZ); /* timers on APB1 run at sysclk */
    RCC_APB1ENR |= RCC_APB1_TIM2 | RCC_APB1_TIM3 | RCC_APB1_TIM4;
    for (i = 0; i < CFG_PWM_CHANNELS; i++) {
        const pwm_pin_t *p = &pwm_map[i];
        uint32_t b = timer_base(p->timer);
        volatile uint32_t *ccmr = p->channel <= 2u ? &TIM_CCMR1(b) : &TIM_CCMR2(b);
        uint32_t shift = (p->channel & 1u) ? 0u : 8u;
        TIM_CCR(b, p->channel) = 0;
        *ccmr = (*ccmr & ~(0xFFu << shift)) | ((6u << 4 | 1u << 3) << shift); /* PWM mode 1, preload */
        TIM_CCER(b) |= 1u << (4u * (p->channel - 1u));
        TIM_PSC(b) = psc ? psc - 1u : 0u;
        TIM_ARR(b) = PWM_COUNTS - 1u;
        TIM_EGR(b) = 1u;
        TIM_CR1(b) = (1u << 7) | 1u; /* ARPE, CEN */
        gpio_mode(p->port, p->pin, GPIO_AF_PP_50MHZ);
    }
}

void hal_pwm_set(uint8_t channel, uint16_t duty)
{
    const pwm_pin_t *p;
    if (channel >= CFG_PWM_CHANNELS) {
        return;
    }
    p = &pwm_map[channel];
    if (duty > 10000u) {
        duty = 10000u;
    }
    /* CCR = ARR + 1 is 100 %, 0 is 0 %: no glitch at either end in PWM mode 1. */
    TIM_CCR(timer_base(p->timer), p->channel) = (uint32_t)duty * PWM_COUNTS / 10000u;
}

/* ------------------------------------------------------------------ I2C1 */

/* Until no START/STOP request is pending: RM0008 §26.6.1 forbids any write to CR1 before
 * the hardware has cleared them (the read-modify-write would request a second one). */
static int8_t i2c_wait_idle(void)
{
    uint32_t t0 = hal_micros();
    while (I2C_CR1 & (I2C_CR1_START | I2C_CR1_STOP)) {
        if ((uint32_t)(hal_micros() - t0) > I2C_STEP_US) {
            return -1;
        }
    }
    return 0;
}

static int8_t i2c_wait(uint32_t mask)
{
    uint32_t t0 = hal_micros();
    while (!(I2C_SR1 & mask)) {
        if (I2C_SR1 & (I2C_SR1_AF | I2C_SR1_BERR | I2C_SR1_ARLO)) {
            return -1;
        }
        if ((uint32_t)(hal_micros() - t0) > I2C_STEP_US) {
            return -1;
        }
    }
    return 0;
}

static void i2c_setup(void)
{
    uint32_t pclk1 = sysclk == 72000000u ? 36000000u : sysclk;
    uint32_t mhz = pclk1 / 1000000u;
    uint32_t ccr = pclk1 / (3u * CFG_I2C_HZ);
    I2C_CR1 = I2C_CR1_SWRST;
    I2C_CR1 = 0;
    I2C_CR2 = mhz;
    I2C_CCR = (1u << 15) | (ccr < 1u ? 1u : ccr); /* fast mode, duty 2 */
    I2C_TRISE = mhz * 300u / 1000u + 1u;
    I2C_CR1 = I2C_CR1_PE;
}

static int8_t i2c_start(uint8_t sla)
{
    I2C_CR1 |= I2C_CR1_START;
    if (i2c_wait(I2C_SR1_SB) != 0) {
        return -1;
    }
    I2C_DR = sla;
    if (i2c_wait(I2C_SR1_ADDR) != 0) {
        return -1;
    }
    return 0;
}

static void clear_addr(void)
{
    volatile uint32_t sr;
    sr = I2C_SR1;
    sr = I2C_SR2;
    (void)sr;
}

static int8_t i2c_transfer(uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
    uint8_t i;
    if (i2c_wait_idle() != 0) {
        return -1;
    }
    if (ntx || !nrx) {
        if (i2c_start((uint8_t)(addr7 << 1)) != 0) {
            return -1;
        }
        clear_addr();
        for (i = 0; i < ntx; i++) {
            if (i2c_wait(I2C_SR1_TXE) != 0) {
                return -1;
            }
            I2C_DR = tx[i];
        }
        if (i2c_wait(I2C_SR1_BTF | (ntx ? 0u : I2C_SR1_TXE)) != 0) {
            return -1;
        }
    }
    if (nrx) {
        I2C_CR1 |= I2C_CR1_ACK;
        if (i2c_start((uint8_t)((addr7 << 1) | 1u)) != 0) {
            return -1;
        }
        if (nrx == 1u) {
            I2C_CR1 &= ~I2C_CR1_ACK;
        }
        clear_addr();
        for (i = 0; i < nrx; i++) {
            if (i + 1u == nrx) {
                /* NACK the last byte and stop after it (set while it is being shifted in). */
                I2C_CR1 &= ~I2C_CR1_ACK;
                I2C_CR1 |= I2C_CR1_STOP;
            }
            if (i2c_wait(I2C_SR1_RXNE) != 0) {
                return -1;
            }
            rx[i] = (uint8_t)I2C_DR;
        }
        return 0;
    }
    I2C_CR1 |= I2C_CR1_STOP;
    return 0;
}

/* Bus recovery (I2C spec UM10204 §3.1.16): a slave cut off mid-byte holds SDA low until it
 * has clocked out its byte. With the peripheral off, clock SCL as GPIO until SDA is released
 * (at most 9 clocks), make a STOP, then set the peripheral up again. A reset of the
 * peripheral alone (SWRST) never frees the bus. */
static void i2c_delay_us(uint32_t us)
{
    uint32_t t0 = hal_micros();
    while ((uint32_t)(hal_micros() - t0) < us) {
    }
}

static void i2c_recover(void)
{
    uint8_t i;
    I2C_CR1 = 0; /* PE off: PB6/PB7 follow their GPIO output latches */
    GPIO_BSRR(GPIOB_BASE) = (1u << 6) | (1u << 7);
    gpio_mode(1, 6, GPIO_OUT_OD_50MHZ);
    gpio_mode(1, 7, GPIO_OUT_OD_50MHZ);
    for (i = 0; i < 9u && !(GPIO_IDR(GPIOB_BASE) & (1u << 7)); i++) {
        GPIO_BRR(GPIOB_BASE) = 1u << 6;
        i2c_delay_us(5u);
        GPIO_BSRR(GPIOB_BASE) = 1u << 6;
        i2c_delay_us(5u);
    }
    GPIO_BRR(GPIOB_BASE) = 1u << 7; /* STOP: SDA rises while SCL is high */
    i2c_delay_us(5u);
    GPIO_BSRR(GPIOB_BASE) = 1u << 7;
    i2c_delay_us(5u);
    gpio_mode(1, 6, GPIO_AF_OD_50MHZ);
    gpio_mode(1, 7, GPIO_AF_OD_50MHZ);
    i2c_setup();
}

static int8_t i2c_write_read(uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
    if (i2c_transfer(addr7, tx, ntx, rx, nrx) != 0) {
        if (I2C_CR1 & I2C_CR1_START) {
            i2c_recover(); /* the START never went out: a line is held low */
            return -1;
        }
        if (!(I2C_CR1 & I2C_CR1_STOP)) {
            I2C_CR1 |= I2C_CR1_STOP;
        }
        I2C_SR1 = 0; /* clear AF/BERR/ARLO */
        if (i2c_wait_idle() != 0 || (I2C_SR2 & I2C_SR2_BUSY)) {
            i2c_recover(); /* bus stuck or a request never completed */
        }
        return -1;
    }
    return 0;
}

static int8_t i2c_result;

/* Not yet in the background on this HAL: the transaction runs here, polled, each step
 * bounded by I2C_STEP_US (≈ 220 µs for a 6-byte read at 400 kHz). */
int8_t hal_i2c_begin(uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
    i2c_result = i2c_write_read(addr7, tx, ntx, rx, nrx);
    return 0;
}

int8_t hal_i2c_poll(void)
{
    return i2c_result;
}

/* ------------------------------------------------------------------ USART1 */

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

/* ------------------------------------------------------------------ the rest */

void hal_init(void)
{
    reset_cause_read(); /* first: RMVF clears the flags for the next reset */
    clock_init();
    RCC_APB2ENR |= RCC_APB2_AFIO | RCC_APB2_IOPA | RCC_APB2_IOPB | RCC_APB2_USART1;
    RCC_APB1ENR |= RCC_APB1_I2C1;
    SYST_RVR = sysclk / 1000u - 1u;
    SYST_CVR = 0;
    SYST_CSR = 7u; /* processor clock, interrupt, enable */
    pwm_init();
    /* I2C1: PB6 = SCL, PB7 = SDA, alternate open-drain. */
    gpio_mode(1, 6, GPIO_AF_OD_50MHZ);
    gpio_mode(1, 7, GPIO_AF_OD_50MHZ);
    i2c_setup();
    /* USART1: PA9 = TX (AF push-pull), PA10 = RX (input, pull-up). */
    gpio_mode(0, 9, GPIO_AF_PP_50MHZ);
    gpio_mode(0, 10, GPIO_IN_PULL);
    GPIO_BSRR(GPIOA_BASE) = 1u << 10;
    USART_BRR = (sysclk + CFG_UART_BAUD / 2u) / CFG_UART_BAUD; /* APB2 = sysclk */
    USART_CR1 = USART_CR1_UE | USART_CR1_TE | USART_CR1_RE | USART_CR1_RXNEIE;
    NVIC_ISER(USART1_IRQN / 32u) = 1u << (USART1_IRQN % 32u);
    iwdg_start(); /* fed by the core's main loop once per completed tick */
}

/* ------------------------------------------------------------------ I2C2 (bus 1)
 * The second bus, PB10 = SCL, PB11 = SDA (RM0008 §9.3.9, no remap), polled like I2C1
 * with the same bounded waits. Only in images whose IMUs use bus 1 (CFG_I2C_BUSES > 1);
 * set up on its first transfer so hal_init stays as it is. */
#if CFG_I2C_BUSES > 1
#define I2C2_BASE 0x40005800u
#define I2C2_CR1 REG32(I2C2_BASE + 0x00u)
#define I2C2_CR2 REG32(I2C2_BASE + 0x04u)
#define I2C2_DR REG32(I2C2_BASE + 0x10u)
#define I2C2_SR1 REG32(I2C2_BASE + 0x14u)
#define I2C2_SR2 REG32(I2C2_BASE + 0x18u)
#define I2C2_CCR REG32(I2C2_BASE + 0x1Cu)
#define I2C2_TRISE REG32(I2C2_BASE + 0x20u)
#define RCC_APB1_I2C2 (1u << 22)

static uint8_t i2c2_ready;

static int8_t i2c2_wait(uint32_t mask)
{
    uint32_t t0 = hal_micros();
    while (!(I2C2_SR1 & mask)) {
        if ((I2C2_SR1 & (I2C_SR1_AF | I2C_SR1_BERR | I2C_SR1_ARLO)) || (uint32_t)(hal_micros() - t0) > I2C_STEP_US) {
            return -1;
        }
    }
    return 0;
}

static void i2c2_setup(void)
{
    uint32_t pclk1 = sysclk == 72000000u ? 36000000u : sysclk;
    uint32_t mhz = pclk1 / 1000000u;
    uint32_t ccr = pclk1 / (3u * CFG_I2C_HZ);
    RCC_APB1ENR |= RCC_APB1_I2C2;
    gpio_mode(1, 10, GPIO_AF_OD_50MHZ);
    gpio_mode(1, 11, GPIO_AF_OD_50MHZ);
    I2C2_CR1 = I2C_CR1_SWRST;
    I2C2_CR1 = 0;
    I2C2_CR2 = mhz;
    I2C2_CCR = (1u << 15) | (ccr < 1u ? 1u : ccr); /* fast mode, duty 2 */
    I2C2_TRISE = mhz * 300u / 1000u + 1u;
    I2C2_CR1 = I2C_CR1_PE;
    i2c2_ready = 1;
}

static int8_t i2c2_start(uint8_t sla)
{
    I2C2_CR1 |= I2C_CR1_START;
    if (i2c2_wait(I2C_SR1_SB) != 0) {
        return -1;
    }
    I2C2_DR = sla;
    return i2c2_wait(I2C_SR1_ADDR);
}

static void i2c2_clear_addr(void)
{
    volatile uint32_t sr;
    sr = I2C2_SR1;
    sr = I2C2_SR2;
    (void)sr;
}

static int8_t i2c2_transfer(uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
    uint8_t i;
    if (ntx || !nrx) {
        if (i2c2_start((uint8_t)(addr7 << 1)) != 0) {
            return -1;
        }
        i2c2_clear_addr();
        for (i = 0; i < ntx; i++) {
            if (i2c2_wait(I2C_SR1_TXE) != 0) {
                return -1;
            }
            I2C2_DR = tx[i];
        }
        if (i2c2_wait(I2C_SR1_BTF | (ntx ? 0u : I2C_SR1_TXE)) != 0) {
            return -1;
        }
    }
    if (nrx) {
        I2C2_CR1 |= I2C_CR1_ACK;
        if (i2c2_start((uint8_t)((addr7 << 1) | 1u)) != 0) {
            return -1;
        }
        if (nrx == 1u) {
            I2C2_CR1 &= ~I2C_CR1_ACK;
        }
        i2c2_clear_addr();
        for (i = 0; i < nrx; i++) {
            if (i + 1u == nrx) {
                I2C2_CR1 &= ~I2C_CR1_ACK;
                I2C2_CR1 |= I2C_CR1_STOP;
            }
            if (i2c2_wait(I2C_SR1_RXNE) != 0) {
                return -1;
            }
            rx[i] = (uint8_t)I2C2_DR;
        }
        return 0;
    }
    I2C2_CR1 |= I2C_CR1_STOP;
    return 0;
}
#endif

int hal_i2c_write_read_bus(uint8_t bus, uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
    if (bus == 0u) {
        return i2c_write_read(addr7, tx, ntx, rx, nrx);
    }
#if CFG_I2C_BUSES > 1
    if (bus == 1u) {
        if (!i2c2_ready) {
            i2c2_setup();
        }
        if (i2c2_transfer(addr7, tx, ntx, rx, nrx) != 0) {
            I2C2_CR1 |= I2C_CR1_STOP;
            I2C2_SR1 = 0; /* clear AF/BERR/ARLO */
            if (I2C2_SR2 & I2C_SR2_BUSY) {
                i2c2_setup(); /* bus stuck: reset the peripheral */
            }
            return -1;
        }
        return 0;
    }
#endif
    (void)addr7;
    (void)tx;
    (void)ntx;
    (void)rx;
    (void)nrx;
    return -1;
}

/* ------------------------------------------------------------------ flash page (hal_nv_*)
 * The block is the start of the last 1 KiB page of the 64 KiB flash (0x0800FC00; the
 * linker script leaves that page out). Programmed through the FPEC (RM0008 §3.3.3;
 * PM0075 §2.3): unlock with KEY1/KEY2, page erase (PER, AR, STRT), then PG and one
 * half-word store at a time, BSY polled after each (erase ≤ 40 ms, program ≤ 70 µs per
 * half-word: DS5319 table 28; the CPU stalls on its flash fetches meanwhile), lock again.
 * The whole write happens in hal_nv_write: the core writes only while no gait runs. The
 * watchdog (33-67 ms) could bite during a 40 ms erase: its prescaler goes from /8 to /16
 * (≥ 66 ms) for the write and back after (RM0008 §19.3.4: PR may change while it runs). */
#define NV_PAGE 0x0800FC00u
#define FLASH_KEYR REG32(0x40022004u)
#define FLASH_SR REG32(0x4002200Cu)
#define FLASH_CR REG32(0x40022010u)
#define FLASH_AR REG32(0x40022014u)
#define FLASH_SR_BSY (1u << 0)
#define FLASH_SR_ERR ((1u << 2) | (1u << 4)) /* PGERR, WRPRTERR */
#define FLASH_SR_EOP (1u << 5)
#define FLASH_CR_PG (1u << 0)
#define FLASH_CR_PER (1u << 1)
#define FLASH_CR_STRT (1u << 6)
#define FLASH_CR_LOCK (1u << 7)

static int8_t nv_result;

static int8_t fpec_wait(void)
{
    uint32_t n = 0;
    while (FLASH_SR & FLASH_SR_BSY) {
        if (++n > 4000000u) { /* far beyond the 40 ms erase at 72 MHz */
            return -1;
        }
    }
    n = FLASH_SR;
    FLASH_SR = FLASH_SR_ERR | FLASH_SR_EOP; /* write 1 to clear */
    return (n & FLASH_SR_ERR) ? -1 : 0;
}

void hal_nv_read(uint8_t *dst, uint8_t n)
{
    const volatile uint8_t *p = (const volatile uint8_t *)NV_PAGE;
    uint8_t i;
    for (i = 0; i < n && i < HAL_NV_BYTES; i++) {
        dst[i] = p[i];
    }
}

int8_t hal_nv_write(const uint8_t *src, uint8_t n)
{
    volatile uint16_t *p = (volatile uint16_t *)NV_PAGE;
    uint8_t i;
    int8_t r;
    uint16_t h;
    if (n > HAL_NV_BYTES) {
        return -1;
    }
    IWDG_KR = 0x5555u;
    IWDG_PR = 2u; /* /16 */
    IWDG_KR = 0xAAAAu;
    if (FLASH_CR & FLASH_CR_LOCK) {
        FLASH_KEYR = 0x45670123u;
        FLASH_KEYR = 0xCDEF89ABu;
    }
    r = fpec_wait();
    FLASH_CR = FLASH_CR_PER;
    FLASH_AR = NV_PAGE;
    FLASH_CR = FLASH_CR_PER | FLASH_CR_STRT;
    r |= fpec_wait();
    FLASH_CR = FLASH_CR_PG;
    for (i = 0; i < n && r == 0; i += 2u) {
        h = (uint16_t)(src[i] | ((i + 1u < n ? src[i + 1u] : 0xFFu) << 8));
        if (h != 0xFFFFu) { /* erased already; programming 0xFFFF is pointless */
            p[i / 2u] = h;
            r |= fpec_wait();
        }
    }
    FLASH_CR = FLASH_CR_LOCK;
    IWDG_KR = 0xAAAAu;
    IWDG_KR = 0x5555u;
    IWDG_PR = 1u; /* /8 again */
    nv_result = r;
    return 0;
}

int8_t hal_nv_poll(void)
{
    return nv_result;
}
