/* hal_avr.c - hal.h for the ATmega328P (Arduino Nano/Uno) at F_CPU (16 MHz).
 *
 * Timer0: free-running /64 (4 µs per count), overflow interrupt → hal_micros (the core
 * paces the control tick on it, so any tick rate works).
 * Timer1 (OC1A = D9, OC1B = D10): fast PWM, TOP = ICR1 for CFG_PWM_HZ, /8.
 * Timer2 (OC2A = D11, OC2B = D3): fast PWM 8 bit, /128 (~490 Hz).
 * Duty 0 and 10000 disconnect the compare output and drive the pin low/high, so "off"
 * is really off (fast PWM with OCR = 0 still gives a one-count pulse).
 * TWI at CFG_I2C_HZ, interrupt-driven (hal_i2c_begin/poll), each transaction bounded by
 * HAL_I2C_DEADLINE_US. USART0 at CFG_UART_BAUD (U2X);
 * its interrupts move bytes to and from the core's rings (uart.h). main() is the core's.
 */
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/wdt.h>
#include <stdint.h>

#include "hal.h"
#include "ring.h"
#include "rom.h"
#include "uart.h"

#include "robot_config.h"

#ifndef F_CPU
#define F_CPU CFG_CLOCK_HZ
#endif
#include <util/delay.h>

#if RING_LARGE
#error "AVR: the UART rings must be at most 128 bytes (8-bit indices are the only atomic ones)"
#endif

/* ------------------------------------------------------------------ time */

static volatile uint32_t t0_overflows;

/* t0_overflows++ by hand: SREG, r24 and Z saved, the count incremented in memory a byte at a time
 * through Z (the carry chain of subi/sbci 0xFF). What avr-gcc makes of the C statement saves r0,
 * r1 and four registers and moves the count with eight 4-byte LDS/STS: this is 50 B of flash,
 * not 74 (R1 on the Nano), and fewer cycles in every overflow. */
ISR(TIMER0_OVF_vect, ISR_NAKED)
{
    __asm__ __volatile__("push r24\n\t"
                         "in r24, __SREG__\n\t"
                         "push r24\n\t"
                         "push r30\n\t"
                         "push r31\n\t"
                         "ldi r30, lo8(%0)\n\t"
                         "ldi r31, hi8(%0)\n\t"
                         "ld r24, Z\n\t"
                         "subi r24, 0xFF\n\t" /* +1: the carry is set unless it wrapped */
                         "st Z+, r24\n\t"
                         "ld r24, Z\n\t"
                         "sbci r24, 0xFF\n\t" /* +1 if the byte below wrapped (carry clear) */
                         "st Z+, r24\n\t"
                         "ld r24, Z\n\t"
                         "sbci r24, 0xFF\n\t"
                         "st Z+, r24\n\t"
                         "ld r24, Z\n\t"
                         "sbci r24, 0xFF\n\t"
                         "st Z, r24\n\t"
                         "pop r31\n\t"
                         "pop r30\n\t"
                         "pop r24\n\t"
                         "out __SREG__, r24\n\t"
                         "pop r24\n\t"
                         "reti" ::"i"(&t0_overflows));
}

uint32_t hal_micros(void)
{
    uint32_t ovf;
    uint8_t cnt;
    uint8_t sreg = SREG;
    cli();
    ovf = t0_overflows;
    cnt = TCNT0;
    if ((TIFR0 & _BV(TOV0)) && cnt < 255u) {
        ovf++; /* overflow pending, not yet counted */
    }
    SREG = sreg;
    return ((ovf << 8) | cnt) * 4u; /* | : the shifted count's low byte is 0 (no carry chain) */
}

/* ------------------------------------------------------------------ PWM */

/* Timer1 TOP for CFG_PWM_HZ at /8, and OCR = duty · TOP / 10000 as a multiply and a
 * shift by precomputed Q16 scales: no division in the tick. */
#define T1_TOP ((uint16_t)(F_CPU / 8u / CFG_PWM_HZ - 1u))
#define T1_SCALE ((uint16_t)(((uint32_t)T1_TOP * 65536u + 9999u) / 10000u))
#define T2_SCALE ((uint16_t)((255UL * 65536u + 9999u) / 10000u))

/* Each PWM channel's compare output (CFG_PWM_MAP names them: HAL_AVR_OC1A = D9, OC1B = D10,
 * OC2A = D11, OC2B = D3), as the row hal_pwm_set reads: its TCCRnA and compare-output enable
 * bit there (COMnA1 or COMnB1), its port and pin, its OCRnx (the low byte of Timer1's 16-bit
 * ones). Data-space addresses, all below 0x100. In flash (no .data bytes); one row read
 * instead of each computed from the output's number (R1 on the Nano: issue 11). */
typedef struct {
    uint8_t tccra, com, port, bit, ocr;
} pwm_row_t;
#define SFR(sfr) ((uint8_t)_SFR_MEM_ADDR(sfr))
#define REG(a) (*(volatile uint8_t *)(uint16_t)(a))
#define HAL_AVR_OC1A {SFR(TCCR1A), _BV(COM1A1), SFR(PORTB), _BV(PB1), SFR(OCR1AL)}
#define HAL_AVR_OC1B {SFR(TCCR1A), _BV(COM1B1), SFR(PORTB), _BV(PB2), SFR(OCR1BL)}
#define HAL_AVR_OC2A {SFR(TCCR2A), _BV(COM2A1), SFR(PORTB), _BV(PB3), SFR(OCR2A)}
#define HAL_AVR_OC2B {SFR(TCCR2A), _BV(COM2B1), SFR(PORTD), _BV(PD3), SFR(OCR2B)}
static const pwm_row_t pwm_map[CFG_PWM_CHANNELS] ROM = CFG_PWM_MAP;

/* Every output starts off: hal_avr_early (.init3, before main) made the pins outputs and drove
 * them low, and nothing has touched them since; the timers' compare outputs start disconnected
 * (TCCR1A and TCCR2A are written here with every COMnx bit 0). That is what hal_pwm_set(ch, 0)
 * leaves, so it is not called again for each channel here, nor the pins set up twice (R1 on
 * the Nano: issue 11). */
static void pwm_init(void)
{
    ICR1 = T1_TOP;
    TCCR1A = _BV(WGM11);
    TCCR1B = _BV(WGM13) | _BV(WGM12) | _BV(CS11);
    TCCR2A = _BV(WGM21) | _BV(WGM20);
    TCCR2B = _BV(CS22) | _BV(CS20);
}

void hal_pwm_set(uint8_t channel, uint16_t duty)
{
    uint8_t com, bit;
    const uint8_t *r;
    volatile uint8_t *tccra, *port, *ocr;
    uint16_t v;
    if (channel >= CFG_PWM_CHANNELS) {
        return;
    }
    r = (const uint8_t *)&pwm_map[channel]; /* the row's fields in order */
    tccra = &REG(ROM_U8(r++));
    com = ROM_U8(r++);
    port = &REG(ROM_U8(r++));
    bit = ROM_U8(r++);
    ocr = &REG(ROM_U8(r));
    if (duty == 0u || duty >= 10000u) {
        /* compare output off: the pin is the port's, low (off) or high (full on) */
        *tccra &= (uint8_t)~com;
        if (duty) {
            *port |= bit;
        } else {
            *port &= (uint8_t)~bit;
        }
        return;
    }
    if (tccra == &TCCR1A) {
        v = (uint16_t)(((uint32_t)duty * T1_SCALE) >> 16);
        ocr[1] = (uint8_t)(v >> 8); /* OCR1xH first (the TEMP register), as OCR1x = v writes it */
    } else {
        v = (uint16_t)(((uint32_t)duty * T2_SCALE) >> 16); /* ≤ 255 */
    }
    *ocr = (uint8_t)v;
    *tccra |= com;
}

/* ------------------------------------------------------------------ I2C (TWI) */

/* One transaction, moved on by the TWI interrupt one bus event at a time (ATmega328P
 * datasheet §22.7, master transmitter and receiver status codes). The main loop only
 * begins it and polls the result; hal_i2c_poll aborts it past its deadline. */
#define TWCR_GO (_BV(TWINT) | _BV(TWEN) | _BV(TWIE))

static struct {
    const uint8_t *tx;
    uint8_t *rx;
    uint8_t sla, ntx, nrx, i;
    uint8_t reading;
    uint8_t unchecked;      /* this transaction's failure is yet to be looked at on the bus */
    volatile int8_t result; /* HAL_I2C_BUSY, 0 or -1 */
    uint32_t t0;
} tw; /* all 0 (.bss, nothing copied at reset): no transaction, nothing to check */

static void twi_done(int8_t r)
{
    TWCR = _BV(TWINT) | _BV(TWEN) | _BV(TWSTO); /* STOP; TWSTO clears when it is out */
    tw.result = r;
}

ISR(TWI_vect)
{
    switch (TWSR & 0xF8u) {
    case 0x08u: /* START */
    case 0x10u: /* repeated START */
        TWDR = (uint8_t)(tw.sla | tw.reading);
        TWCR = TWCR_GO;
        break;
    case 0x18u: /* SLA+W ACKed */
    case 0x28u: /* data byte ACKed */
        if (tw.i < tw.ntx) {
            TWDR = tw.tx[tw.i++];
            TWCR = TWCR_GO;
        } else if (tw.nrx) {
            tw.reading = 1;
            tw.i = 0;
            TWCR = TWCR_GO | _BV(TWSTA);
        } else {
            twi_done(0);
        }
        break;
    case 0x50u: /* data byte received, ACK returned */
        tw.rx[tw.i++] = TWDR;
        /* fall through */
    case 0x40u: /* SLA+R ACKed */
        TWCR = (uint8_t)(TWCR_GO | ((uint8_t)(tw.i + 1u) < tw.nrx ? _BV(TWEA) : 0u)); /* i < nrx ≤ 255 */
        break;
    case 0x58u: /* last byte received, NACK returned */
        tw.rx[tw.i] = TWDR;
        twi_done(0);
        break;
    default: /* SLA or data NACKed, arbitration lost, bus error */
        twi_done(-1);
        break;
    }
}

/* UM10204 §3.1.16: a slave cut off mid-byte holds SDA low until it has clocked its byte
 * out. With the TWI off, clock SCL (PC5) 9 times (enough for any byte and its ACK; a
 * free slave ignores them), then a STOP; then the TWI again. Bounded: about 100 µs, and
 * only after a failure. */
static void twi_recover(void)
{
    uint8_t k;
    TWCR = 0;
    PORTC &= (uint8_t) ~(_BV(PC4) | _BV(PC5));
    for (k = 0; k < 9u; k++) {
        DDRC |= _BV(PC5); /* SCL low */
        _delay_us(5);
        DDRC &= (uint8_t)~_BV(PC5); /* released: the pull-up takes it high */
        _delay_us(5);
    }
    DDRC |= _BV(PC4); /* STOP: SDA low, then released while SCL is high */
    _delay_us(5);
    DDRC &= (uint8_t)~_BV(PC4);
    PORTC |= _BV(PC4) | _BV(PC5);
    _delay_us(5);
    TWCR = _BV(TWEN);
}

int8_t hal_i2c_begin(uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
    if (hal_i2c_poll() == HAL_I2C_BUSY) {
        return -1;
    }
    tw.tx = tx;
    tw.rx = rx;
    tw.sla = (uint8_t)(addr7 << 1);
    tw.ntx = ntx;
    tw.nrx = nrx;
    tw.i = 0;
    tw.reading = ntx ? 0u : 1u;
    tw.t0 = hal_micros();
    tw.unchecked = 1;
    tw.result = HAL_I2C_BUSY;
    TWCR = TWCR_GO | _BV(TWSTA);
    return 0;
}

/* The transaction (or its STOP) is past its deadline. One copy for both checks. */
static uint8_t __attribute__((noinline)) twi_late(void)
{
    return (uint32_t)(hal_micros() - tw.t0) > HAL_I2C_DEADLINE_US;
}

int8_t hal_i2c_poll(void)
{
    int8_t r = tw.result;
    if (r == HAL_I2C_BUSY) {
        if (!twi_late()) {
            return HAL_I2C_BUSY;
        }
        TWCR = 0; /* abort: the interrupt cannot run again */
        tw.result = r = -1;
        tw.unchecked = 0;
        twi_recover();
        return r;
    }
    if (TWCR & _BV(TWSTO)) {
        if (!twi_late()) {
            return HAL_I2C_BUSY; /* the STOP is still going out */
        }
        twi_recover();
        return -1;
    }
    if (r < 0 && tw.unchecked) {
        tw.unchecked = 0;
        if (!(PINC & _BV(PC4))) {
            twi_recover(); /* a slave kept SDA low */
        }
    }
    return r;
}

/* ------------------------------------------------------------------ USART0 */

ISR(USART_RX_vect)
{
    (void)uart_isr_rx(UDR0);
}

ISR(USART_UDRE_vect)
{
    int b = uart_isr_tx();
    if (b < 0) {
        UCSR0B &= (uint8_t)~_BV(UDRIE0);
        return;
    }
    UDR0 = (uint8_t)b;
}

void hal_uart_tx_start(void)
{
    UCSR0B |= _BV(UDRIE0);
}

/* ------------------------------------------------------------------ reset, watchdog, markers */

/* MCUSR keeps its flags across resets until cleared, and after a watchdog reset WDRF
 * keeps the watchdog on (15 ms): both are handled first thing, before the C runtime
 * initialises RAM (.init3), together with driving the MOSFET gates low (the pins are
 * high-impedance inputs from reset until here). */
uint8_t hal_avr_mcusr __attribute__((section(".noinit")));

void hal_avr_early(void) __attribute__((naked, used, section(".init3")));
void hal_avr_early(void)
{
    hal_avr_mcusr = MCUSR;
    MCUSR = 0;
    wdt_disable();
    PORTB &= (uint8_t) ~(_BV(PB1) | _BV(PB2) | _BV(PB3));
    PORTD &= (uint8_t)~_BV(PD3);
    DDRB |= _BV(PB1) | _BV(PB2) | _BV(PB3);
    DDRD |= _BV(PD3);
}

uint8_t hal_reset_cause(void)
{
    uint8_t f = hal_avr_mcusr;
    /* ATmega328P datasheet §10.9.1: several flags may be set; the watchdog wins, and
     * power-on over brown-out (a power-on also trips the brown-out detector). */
    return (f & _BV(WDRF))    ? HAL_RESET_WATCHDOG
           : (f & _BV(PORF))  ? HAL_RESET_POWER_ON
           : (f & _BV(BORF))  ? HAL_RESET_BROWN_OUT
           : (f & _BV(EXTRF)) ? HAL_RESET_EXTERNAL
                              : HAL_RESET_UNKNOWN;
}

void hal_watchdog_feed(void)
{
    wdt_reset();
}

void hal_tick_mark(uint8_t busy)
{
    GPIOR0 = busy;
}

/* Watchdog period: at least four ticks, 60 ms nominal for every tick rate of 100 Hz and
 * up (datasheet table 10-3; the oscillator is ±10 % or worse with voltage). */
#if CFG_TICK_US <= 15000u
#define HAL_WDTO WDTO_60MS
#else
#define HAL_WDTO WDTO_250MS
#endif

/* ------------------------------------------------------------------ the rest */

void hal_init(void)
{
    cli();
    /* Timer0: normal mode, /64. */
    TCCR0A = 0;
    TCCR0B = _BV(CS01) | _BV(CS00);
    TIMSK0 = _BV(TOIE0);
    pwm_init();
    /* TWI: SCL = F_CPU / (16 + 2·TWBR), prescaler 1. Internal pull-ups as a fallback. */
    PORTC |= _BV(PC4) | _BV(PC5);
    TWSR = 0;
    TWBR = (uint8_t)((F_CPU / CFG_I2C_HZ - 16u) / 2u);
    TWCR = _BV(TWEN);
    /* USART0, 8N1, double speed. */
    UCSR0A = _BV(U2X0);
    UBRR0 = (uint16_t)((F_CPU + 4u * CFG_UART_BAUD) / (8u * CFG_UART_BAUD) - 1u);
    UCSR0C = _BV(UCSZ01) | _BV(UCSZ00);
    UCSR0B = _BV(RXEN0) | _BV(TXEN0) | _BV(RXCIE0);
    wdt_enable(HAL_WDTO);
    sei();
}

/* ------------------------------------------------------------------ EEPROM (hal_nv_*)
 * The block is EEPROM 0..HAL_NV_BYTES-1 (ATmega328P datasheet §8.4: 1 KiB, 3.4 ms per
 * erase+write of one byte, EEMPE then EEPE within four cycles, interrupts off between).
 * One changed byte begun per poll, never waiting on a write in flight; unchanged bytes
 * are not rewritten (100,000 cycles per cell). */
static struct {
    const uint8_t *src; /* the block being written, 0: none */
    uint8_t n, i;
} nv;

void hal_nv_read(uint8_t *dst, uint8_t n)
{
    uint8_t i;
    for (i = 0; i < n && i < HAL_NV_BYTES; i++) {
        while (EECR & _BV(EEPE)) {
        } /* bounded: the write in flight ends within 3.4 ms */
        EEAR = i;
        EECR |= _BV(EERE);
        dst[i] = EEDR;
    }
}

int8_t hal_nv_write(const uint8_t *src, uint8_t n)
{
    if (n > HAL_NV_BYTES || nv.src) {
        return -1;
    }
    nv.src = src;
    nv.n = n;
    nv.i = 0;
    return 0;
}

int8_t hal_nv_poll(void)
{
    uint8_t sreg;
    if (!nv.src) {
        return 0;
    }
    for (;;) {
        if (EECR & _BV(EEPE)) {
            return HAL_NV_BUSY;
        }
        if (nv.i >= nv.n) {
            nv.src = 0;
            return 0;
        }
        EEAR = nv.i;
        EECR |= _BV(EERE);
        if (EEDR != nv.src[nv.i]) {
            EEDR = nv.src[nv.i++];
            sreg = SREG;
            cli();
            /* EEMPE, then EEPE within four cycles (ATmega328P datasheet §8.6.3), in asm: C
             * leaves the instruction choice to the compiler, and with this board's flags
             * avr-gcc 5.4 once made it st/ld/ori/st through Z (7 cycles), so no byte was ever
             * written. OUT then SBI: EEPE set 1 cycle after EEMPE. EEPM = 0: erase and write. */
            __asm__ __volatile__("out %[eecr], %[mpe]\n\t"
                                 "sbi %[eecr], %[pe]"
                                 :
                                 : [eecr] "I"(_SFR_IO_ADDR(EECR)), [mpe] "r"((uint8_t)_BV(EEMPE)), [pe] "I"(EEPE)
                                 : "memory");
            SREG = sreg;
            return HAL_NV_BUSY;
        }
        nv.i++;
    }
}
