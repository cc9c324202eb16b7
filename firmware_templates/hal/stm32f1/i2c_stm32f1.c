/* i2c_stm32f1.c - hal_i2c_begin/begin_bus/poll on the STM32F103's I2C1 and I2C2, in the
 * background. Part of the stm32f1 HAL (hal_stm32f1.h).
 *
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

#include <stdint.h>

#include "hal.h"
#include "hal_stm32f1.h"
#include "robot_config.h"

#define I2C_STEP_US 300u
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

void i2c_setup(uint8_t bus)
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
