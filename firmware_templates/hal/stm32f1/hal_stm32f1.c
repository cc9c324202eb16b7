/* hal_stm32f1.c - hal.h for the STM32F103 ("Blue Pill"), bare-metal registers.
 *
 * Clock: 8 MHz HSE × 9 = 72 MHz (APB1 36 MHz, APB2 72 MHz); if the crystal does not
 * start, the board runs on the 8 MHz HSI and every divider below follows `sysclk`.
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
static uint32_t systick_load; /* SYST_RVR + 1, set with it in hal_init: one register read less per hal_micros */
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
    if (duty == 0u) {
        /* Off now, not at the end of the running PWM period: with the preload off for the
         * write, CCR takes the new value at once (RM0008 §15.3.9, OCxPE) and PWM mode 1 drops
         * the output as CNT >= 0; the counter, so every other channel, is not disturbed. */
        uint32_t b = timer_base(p->timer);
        volatile uint32_t *ccmr = p->channel <= 2u ? &TIM_CCMR1(b) : &TIM_CCMR2(b);
        uint32_t pe = (1u << 3) << ((p->channel & 1u) ? 0u : 8u);
        *ccmr &= ~pe;
        TIM_CCR(b, p->channel) = 0;
        *ccmr |= pe;
        return;
    }
    TIM_CCR(timer_base(p->timer), p->channel) = (uint32_t)duty * PWM_COUNTS / 10000u;
}

/* ------------------------------------------------------------------ I2C1, I2C2
 * Bus 0 = I2C1 on PB6 (SCL) / PB7 (SDA); bus 1 = I2C2 on PB10 / PB11 (RM0008 §9.3.9, no
 * remap), only in images whose IMUs use it (CFG_I2C_BUSES > 1; set up on first use, so
 * hal_init stays as it is). One transaction at a time over both buses, in the background:
 * hal_i2c_begin_bus() starts it, every hal_i2c_poll() moves it on as far as the status
 * flags allow and never waits. The receive side follows RM0008 §26.3.3 so that it is right
 * however late a poll comes (the peripheral stretches SCL while the core is away):
 *   1 byte:  ACK = 0 before ADDR is cleared, STOP right after, RxNE, read;
 *   2 bytes: POS = 1 and ACK = 1 before START; clear ADDR, ACK = 0; BTF; STOP; read twice;
 *   N > 2:   read on RxNE until 3 are left; BTF, ACK = 0, read N-2; BTF, STOP, read N-1;
 *            RxNE, read N.
 * The two steps that must follow ADDR within one byte time (≈ 22 µs at 400 kHz) run with
 * interrupts off. A NACK, a bus error or HAL_I2C_DEADLINE_US without completion ends the
 * transaction with -1: a STOP, then, if the bus does not come free within I2C_STEP_US,
 * the 9-clock recovery. START is never requested while a STOP is still pending (§26.6.1). */

#define I2C2_BASE 0x40005800u
#define RCC_APB1_I2C2 (1u << 22)
#define I2C_CR1_POS (1u << 11)
#define I2CR(b, off) REG32((b) + (off))
#define CR1(b) I2CR(b, 0x00u)
#define DR(b) I2CR(b, 0x10u)
#define SR1(b) I2CR(b, 0x14u)
#define SR2(b) I2CR(b, 0x18u)
#define I2C_ERRORS (I2C_SR1_AF | I2C_SR1_BERR | I2C_SR1_ARLO)

enum {
    X_IDLE,   /* no transaction; `result` is the last one's */
    X_FREE,   /* waiting for the previous STOP to clear */
    X_SB_W,   /* START requested (write) */
    X_ADDR_W, /* address + W sent */
    X_TX,     /* sending tx */
    X_SB_R,   /* (repeated) START requested (read) */
    X_ADDR_R, /* address + R sent */
    X_RX,     /* receiving */
    X_CLOSE   /* failed: STOP sent, waiting for the bus to come free */
};

static struct {
    uint32_t base;
    uint32_t t0; /* hal_micros() at begin, or at the failure for X_CLOSE */
    const uint8_t *tx;
    uint8_t *rx;
    uint8_t addr, ntx, nrx, i, state, bus;
    int8_t result;
} xf;
static uint8_t i2c_ready; /* bit per bus: set up */

static void i2c_setup(uint8_t bus)
{
    uint32_t b = bus ? I2C2_BASE : I2C1_BASE;
    uint32_t pclk1 = sysclk == 72000000u ? 36000000u : sysclk;
    uint32_t mhz = pclk1 / 1000000u;
    uint32_t ccr = pclk1 / (3u * CFG_I2C_HZ);
    uint8_t scl = bus ? 10u : 6u;
    RCC_APB1ENR |= bus ? RCC_APB1_I2C2 : RCC_APB1_I2C1;
    gpio_mode(1, scl, GPIO_AF_OD_50MHZ);
    gpio_mode(1, (uint8_t)(scl + 1u), GPIO_AF_OD_50MHZ);
    CR1(b) = I2C_CR1_SWRST;
    CR1(b) = 0;
    I2CR(b, 0x04u) = mhz;                                  /* CR2.FREQ */
    I2CR(b, 0x1Cu) = (1u << 15) | (ccr < 1u ? 1u : ccr);   /* CCR: fast mode, duty 2 */
    I2CR(b, 0x20u) = mhz * 300u / 1000u + 1u;              /* TRISE: 300 ns */
    CR1(b) = I2C_CR1_PE;
    i2c_ready = (uint8_t)(i2c_ready | (1u << bus));
}

/* Bus recovery (I2C spec UM10204 §3.1.16): a slave cut off mid-byte holds SDA low until it
 * has clocked out its byte. With the peripheral off, clock SCL as GPIO until SDA is released
 * (at most 9 clocks), make a STOP, then set the peripheral up again. A reset of the
 * peripheral alone (SWRST) never frees the bus. Blocks ≈ 100 µs; only after a failure. */
static void i2c_delay_us(uint32_t us)
{
    uint32_t t0 = hal_micros();
    while ((uint32_t)(hal_micros() - t0) < us) {
    }
}

static void i2c_recover(uint8_t bus)
{
    uint8_t i, scl = bus ? 10u : 6u, sda = (uint8_t)(scl + 1u);
    CR1(bus ? I2C2_BASE : I2C1_BASE) = 0; /* PE off: the pins follow their GPIO latches */
    GPIO_BSRR(GPIOB_BASE) = (1u << scl) | (1u << sda);
    gpio_mode(1, scl, GPIO_OUT_OD_50MHZ);
    gpio_mode(1, sda, GPIO_OUT_OD_50MHZ);
    for (i = 0; i < 9u && !(GPIO_IDR(GPIOB_BASE) & (1u << sda)); i++) {
        GPIO_BRR(GPIOB_BASE) = 1u << scl;
        i2c_delay_us(5u);
        GPIO_BSRR(GPIOB_BASE) = 1u << scl;
        i2c_delay_us(5u);
    }
    GPIO_BRR(GPIOB_BASE) = 1u << sda; /* STOP: SDA rises while SCL is high */
    i2c_delay_us(5u);
    GPIO_BSRR(GPIOB_BASE) = 1u << sda;
    i2c_delay_us(5u);
    i2c_setup(bus);
}

/* Interrupts off, and back to what they were (a caller may already have them off). */
static uint32_t irq_off(void)
{
    uint32_t primask;
    __asm volatile("mrs %0, primask\n\tcpsid i" : "=r"(primask)::"memory");
    return primask;
}

static void irq_restore(uint32_t primask)
{
    __asm volatile("msr primask, %0" ::"r"(primask) : "memory");
}

static void clear_addr(uint32_t b)
{
    volatile uint32_t sr;
    sr = SR1(b);
    sr = SR2(b);
    (void)sr;
}

static void x_fail(uint32_t now)
{
    uint32_t b = xf.base;
    if (!(CR1(b) & (I2C_CR1_START | I2C_CR1_STOP))) {
        CR1(b) = (CR1(b) & ~(I2C_CR1_ACK | I2C_CR1_POS)) | I2C_CR1_STOP;
    }
    SR1(b) = 0; /* clear AF/BERR/ARLO */
    xf.result = -1;
    xf.t0 = now;
    xf.state = X_CLOSE;
}

static void x_start_read(uint32_t b)
{
    /* 2 bytes: POS and ACK before the START (RM0008 §26.3.3); otherwise ACK, POS off. */
    CR1(b) = (CR1(b) & ~I2C_CR1_POS) | I2C_CR1_ACK | (xf.nrx == 2u ? I2C_CR1_POS : 0u) | I2C_CR1_START;
    xf.state = X_SB_R;
}

/* A transaction waiting on the bus: past its deadline it fails; a failed one's STOP must
 * free the bus within I2C_STEP_US, or the bus is recovered. */
static void x_timeout(uint32_t now)
{
    uint32_t b = xf.base;
    if (xf.state == X_CLOSE) {
        if (!(CR1(b) & (I2C_CR1_START | I2C_CR1_STOP)) && !(SR2(b) & I2C_SR2_BUSY)) {
            xf.state = X_IDLE;
        } else if ((uint32_t)(now - xf.t0) > I2C_STEP_US) {
            i2c_recover(xf.bus); /* a START that never went out or a STOP that cannot: a line is held */
            xf.state = X_IDLE;
        }
    } else if ((uint32_t)(now - xf.t0) > HAL_I2C_DEADLINE_US) {
        x_fail(now);
    }
}

/* One step of the transaction on what the status flags say now: 0 when it waits on the bus
 * (then hal_i2c_poll checks the time), 1 when it moved on and the next flag may already be
 * up, 2 when it moved on and the next flag needs the bus. */
static uint8_t x_step(void)
{
    uint32_t b = xf.base;
    uint32_t sr1, primask;
    if (xf.state == X_CLOSE) {
        return 0;
    }
    if (xf.state == X_FREE) {
        if (CR1(b) & (I2C_CR1_START | I2C_CR1_STOP)) {
            return 0;
        }
        if (xf.ntx || !xf.nrx) {
            CR1(b) = (CR1(b) & ~I2C_CR1_POS) | I2C_CR1_START;
            xf.state = X_SB_W;
        } else {
            x_start_read(b);
        }
        return 2;
    }
    sr1 = SR1(b);
    if (sr1 & I2C_ERRORS) {
        x_fail(hal_micros());
        return 2;
    }
    switch (xf.state) {
    case X_SB_W:
    case X_SB_R:
        if (!(sr1 & I2C_SR1_SB)) {
            return 0;
        }
        DR(b) = (uint32_t)(xf.addr << 1) | (xf.state == X_SB_R ? 1u : 0u);
        xf.state++;
        return 2;
    case X_ADDR_W:
        if (!(sr1 & I2C_SR1_ADDR)) {
            return 0;
        }
        clear_addr(b);
        xf.i = 0;
        xf.state = X_TX;
        return 1;
    case X_TX:
        if (xf.i < xf.ntx) {
            if (!(sr1 & I2C_SR1_TXE)) {
                return 0;
            }
            DR(b) = xf.tx[xf.i++];
            return 1;
        }
        if (!(sr1 & (xf.ntx ? I2C_SR1_BTF : (I2C_SR1_BTF | I2C_SR1_TXE)))) {
            return 0;
        }
        if (xf.nrx) {
            x_start_read(b); /* repeated START: no STOP is pending here */
        } else {
            CR1(b) |= I2C_CR1_STOP;
            xf.result = 0;
            xf.state = X_IDLE;
        }
        return 2;
    case X_ADDR_R:
        if (!(sr1 & I2C_SR1_ADDR)) {
            return 0;
        }
        xf.i = 0;
        primask = irq_off();
        if (xf.nrx == 1u) {
            CR1(b) &= ~I2C_CR1_ACK;
            clear_addr(b);
            CR1(b) |= I2C_CR1_STOP;
        } else {
            clear_addr(b);
            if (xf.nrx == 2u) {
                CR1(b) &= ~I2C_CR1_ACK; /* with POS: NACKs the second byte */
            }
        }
        irq_restore(primask);
        xf.state = X_RX;
        return 2;
    default: /* X_RX */
    {
        uint8_t left = (uint8_t)(xf.nrx - xf.i);
        if (left == 1u) {
            if (!(sr1 & I2C_SR1_RXNE)) {
                return 0;
            }
            xf.rx[xf.i++] = (uint8_t)DR(b); /* POS is cleared with the next START (no CR1 write while STOP is pending) */
            xf.result = 0;
            xf.state = X_IDLE;
            return 2;
        }
        if (left > 3u) {
            if (!(sr1 & I2C_SR1_RXNE)) {
                return 0;
            }
            xf.rx[xf.i++] = (uint8_t)DR(b);
            return 1;
        }
        if (!(sr1 & I2C_SR1_BTF)) {
            return 0;
        }
        if (left == 3u) {
            CR1(b) &= ~I2C_CR1_ACK; /* applies to byte N: N-1 is held, already ACKed */
        } else {
            CR1(b) |= I2C_CR1_STOP; /* left == 2: both in; N was NACKed */
            if (xf.nrx == 2u) { /* POS: both bytes in, the second NACKed */
                xf.rx[xf.i++] = (uint8_t)DR(b);
                xf.rx[xf.i++] = (uint8_t)DR(b);
                xf.result = 0;
                xf.state = X_IDLE;
                return 2;
            }
        }
        xf.rx[xf.i++] = (uint8_t)DR(b);
        return 1;
    }
    }
}

int8_t hal_i2c_begin_bus(uint8_t bus, uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
    if (hal_i2c_poll() == HAL_I2C_BUSY || bus >= CFG_I2C_BUSES || bus > 1u) {
        return -1;
    }
    if (!(i2c_ready & (1u << bus))) {
        i2c_setup(bus);
    }
    xf.base = bus ? I2C2_BASE : I2C1_BASE;
    xf.bus = bus;
    xf.addr = addr7;
    xf.tx = tx;
    xf.ntx = ntx;
    xf.rx = rx;
    xf.nrx = nrx;
    xf.t0 = hal_micros();
    xf.result = HAL_I2C_BUSY;
    xf.state = X_FREE;
    (void)hal_i2c_poll(); /* the START goes out now if the bus is free */
    return 0;
}

int8_t hal_i2c_begin(uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
    return hal_i2c_begin_bus(0, addr7, tx, ntx, rx, nrx);
}

int8_t hal_i2c_poll(void)
{
    uint8_t n = 8, r; /* bounded: at most a few bytes' worth of flags per call */
    while (xf.state != X_IDLE) {
        r = x_step();
        if (r == 0u) {
            x_timeout(hal_micros()); /* the clock only when waiting: fewer reads per poll */
            break;
        }
        if (r == 2u || --n == 0u) {
            break;
        }
    }
    return xf.state == X_IDLE ? xf.result : HAL_I2C_BUSY;
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
    SYST_RVR = sysclk / 1000u - 1u;
    systick_load = sysclk / 1000u;
    SYST_CVR = 0;
    SYST_CSR = 7u; /* processor clock, interrupt, enable */
    pwm_init();
    i2c_setup(0); /* I2C1: PB6 = SCL, PB7 = SDA, alternate open-drain */
    /* USART1: PA9 = TX (AF push-pull), PA10 = RX (input, pull-up). */
    gpio_mode(0, 9, GPIO_AF_PP_50MHZ);
    gpio_mode(0, 10, GPIO_IN_PULL);
    GPIO_BSRR(GPIOA_BASE) = 1u << 10;
    USART_BRR = (sysclk + CFG_UART_BAUD / 2u) / CFG_UART_BAUD; /* APB2 = sysclk */
    USART_CR1 = USART_CR1_UE | USART_CR1_TE | USART_CR1_RE | USART_CR1_RXNEIE;
    NVIC_ISER(USART1_IRQN / 32u) = 1u << (USART1_IRQN % 32u);
    iwdg_start(); /* fed by the core's main loop once per completed tick */
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
