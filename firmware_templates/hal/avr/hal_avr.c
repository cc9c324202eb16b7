/* hal_avr.c - hal.h for the ATmega328P (Arduino Nano/Uno) at F_CPU (16 MHz).
 *
 * Timer0: free-running /64 (4 µs per count), overflow interrupt → hal_micros (the core
 * paces the control tick on it, so any tick rate works).
 * Timer1 (OC1A = D9, OC1B = D10): fast PWM, TOP = ICR1 for CFG_PWM_HZ, /8.
 * Timer2 (OC2A = D11, OC2B = D3): fast PWM 8 bit, /128 (~490 Hz).
 * Duty 0 and 10000 disconnect the compare output and drive the pin low/high, so "off"
 * is really off (fast PWM with OCR = 0 still gives a one-count pulse).
 * TWI at CFG_I2C_HZ, every wait bounded by TWI_STEP_US. USART0 at CFG_UART_BAUD (U2X);
 * its interrupts move bytes to and from the core's rings (uart.h). main() is the core's.
 */
#include <avr/interrupt.h>
#include <avr/io.h>
#include <stdint.h>

#include "hal.h"
#include "ring.h"
#include "uart.h"

enum { HAL_AVR_OC1A, HAL_AVR_OC1B, HAL_AVR_OC2A, HAL_AVR_OC2B };

#include "robot_config.h"

#ifndef F_CPU
#define F_CPU CFG_CLOCK_HZ
#endif

#if RING_LARGE
#error "AVR: the UART rings must be at most 128 bytes (8-bit indices are the only atomic ones)"
#endif
#define TWI_STEP_US 400u

static const uint8_t pwm_map[CFG_PWM_CHANNELS] = CFG_PWM_MAP;

/* ------------------------------------------------------------------ time */

static volatile uint32_t t0_overflows;

ISR(TIMER0_OVF_vect)
{
    t0_overflows++;
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
    return ((ovf << 8) + cnt) * 4u;
}

/* ------------------------------------------------------------------ PWM */

static uint16_t t1_top;

static void pin_out(uint8_t oc, uint8_t high)
{
    volatile uint8_t *port = (oc == HAL_AVR_OC2B) ? &PORTD : &PORTB;
    uint8_t bit = (oc == HAL_AVR_OC1A) ? _BV(PB1) : (oc == HAL_AVR_OC1B) ? _BV(PB2) : (oc == HAL_AVR_OC2A) ? _BV(PB3) : _BV(PD3);
    if (high) {
        *port |= bit;
    } else {
        *port &= (uint8_t)~bit;
    }
}

static void pwm_init(void)
{
    uint8_t ch;
    DDRB |= _BV(PB1) | _BV(PB2) | _BV(PB3);
    DDRD |= _BV(PD3);
    PORTB &= (uint8_t) ~(_BV(PB1) | _BV(PB2) | _BV(PB3));
    PORTD &= (uint8_t)~_BV(PD3);
    t1_top = (uint16_t)(F_CPU / 8u / CFG_PWM_HZ - 1u);
    ICR1 = t1_top;
    TCCR1A = _BV(WGM11);
    TCCR1B = _BV(WGM13) | _BV(WGM12) | _BV(CS11);
    TCCR2A = _BV(WGM21) | _BV(WGM20);
    TCCR2B = _BV(CS22) | _BV(CS20);
    for (ch = 0; ch < CFG_PWM_CHANNELS; ch++) {
        hal_pwm_set(ch, 0);
    }
}

void hal_pwm_set(uint8_t channel, uint16_t duty)
{
    uint8_t oc, full, off;
    if (channel >= CFG_PWM_CHANNELS) {
        return;
    }
    oc = pwm_map[channel];
    full = duty >= 10000u;
    off = duty == 0u;
    switch (oc) {
    case HAL_AVR_OC1A:
        if (off || full) {
            TCCR1A &= (uint8_t)~_BV(COM1A1);
        } else {
            OCR1A = (uint16_t)((uint32_t)duty * t1_top / 10000u);
            TCCR1A |= _BV(COM1A1);
        }
        break;
    case HAL_AVR_OC1B:
        if (off || full) {
            TCCR1A &= (uint8_t)~_BV(COM1B1);
        } else {
            OCR1B = (uint16_t)((uint32_t)duty * t1_top / 10000u);
            TCCR1A |= _BV(COM1B1);
        }
        break;
    case HAL_AVR_OC2A:
        if (off || full) {
            TCCR2A &= (uint8_t)~_BV(COM2A1);
        } else {
            OCR2A = (uint8_t)((uint32_t)duty * 255u / 10000u);
            TCCR2A |= _BV(COM2A1);
        }
        break;
    default:
        if (off || full) {
            TCCR2A &= (uint8_t)~_BV(COM2B1);
        } else {
            OCR2B = (uint8_t)((uint32_t)duty * 255u / 10000u);
            TCCR2A |= _BV(COM2B1);
        }
        break;
    }
    if (off || full) {
        pin_out(oc, full);
    }
}

/* ------------------------------------------------------------------ I2C (TWI) */

static int8_t twi_wait(void)
{
    uint32_t t0 = hal_micros();
    while (!(TWCR & _BV(TWINT))) {
        if ((uint32_t)(hal_micros() - t0) > TWI_STEP_US) {
            return -1;
        }
    }
    return 0;
}

static void twi_stop(void)
{
    uint32_t t0 = hal_micros();
    TWCR = _BV(TWINT) | _BV(TWEN) | _BV(TWSTO);
    while ((TWCR & _BV(TWSTO)) && (uint32_t)(hal_micros() - t0) < TWI_STEP_US) {
    }
}

static void twi_recover(void)
{
    TWCR = 0; /* release the bus, then re-enable */
    TWCR = _BV(TWEN);
}

static int8_t twi_start(uint8_t sla, uint8_t expect_start, uint8_t expect_ack)
{
    TWCR = _BV(TWINT) | _BV(TWSTA) | _BV(TWEN);
    if (twi_wait() || (TWSR & 0xF8u) != expect_start) {
        return -1;
    }
    TWDR = sla;
    TWCR = _BV(TWINT) | _BV(TWEN);
    if (twi_wait() || (TWSR & 0xF8u) != expect_ack) {
        return -1;
    }
    return 0;
}

static int twi_transfer(uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
    uint8_t i;
    if (ntx) {
        if (twi_start((uint8_t)(addr7 << 1), 0x08u, 0x18u)) {
            return -1;
        }
        for (i = 0; i < ntx; i++) {
            TWDR = tx[i];
            TWCR = _BV(TWINT) | _BV(TWEN);
            if (twi_wait() || (TWSR & 0xF8u) != 0x28u) {
                return -1;
            }
        }
    }
    if (nrx) {
        if (twi_start((uint8_t)((addr7 << 1) | 1u), ntx ? 0x10u : 0x08u, 0x40u)) {
            return -1;
        }
        for (i = 0; i < nrx; i++) {
            uint8_t last = (uint8_t)(i + 1u == nrx);
            TWCR = (uint8_t)(_BV(TWINT) | _BV(TWEN) | (last ? 0u : _BV(TWEA)));
            if (twi_wait()) {
                return -1;
            }
            rx[i] = TWDR;
        }
    }
    twi_stop();
    return 0;
}

int hal_i2c_write_read(uint8_t addr7, const uint8_t *tx, uint8_t ntx, uint8_t *rx, uint8_t nrx)
{
    if (twi_transfer(addr7, tx, ntx, rx, nrx) != 0) {
        twi_stop();
        twi_recover();
        return -1;
    }
    return 0;
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
    sei();
}
