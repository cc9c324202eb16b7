/* twi.c - the ATmega328P TWI (I2C master) on the bus of i2cbus.c, with the chip's timing.
 *
 * Replaces simavr 1.6's avr_twi, whose master mode differs from the chip in ways a
 * driver can see (docs/emulators-avr.md):
 *   - SLA+W answered with status 0x28 (data ACK) instead of 0x18 when TWDR was written
 *     before the address phase, which is how every driver sends the address;
 *   - TWINT: right after TWCR = TWINT|TWEN for the address it still reads 1 and TWSR
 *     already holds the final status; writing TWCR with TWINT = 0 clears it;
 *   - every TWI "bit" takes 1 µs whatever TWBR and TWPS say (a 9-bit byte is 9 µs, so
 *     400 kHz I2C looks 2.5 times faster than it is), and START or the SLA+W above
 *     complete in 8 CPU cycles.
 * Here the registers TWBR, TWSR, TWAR, TWDR, TWCR and TWAMR are ours (simavr's read and
 * write callbacks for them are replaced after avr_init). Master transmitter and receiver
 * as in the datasheet (§22.6-22.7): SCL period = 16 + 2·TWBR·4^TWPS CPU cycles; START,
 * repeated START and STOP take one SCL period, an address or data byte with its
 * acknowledge nine; TWINT is set when an operation completes (interrupt TWI_vect = 24
 * when TWIE is set, re-entered while TWINT and TWIE stay set) and cleared only by
 * writing one to it, which starts the next operation; TWSR reads 0xF8 while TWINT is
 * clear; a TWDR write while TWINT is clear sets TWWC and is ignored; TWSTO clears itself
 * once the STOP is on the bus. Slave mode is not modelled (TWAR/TWAMR read back only).
 *
 * The bus: who answers at an address is i2cbus.c's (the MPU-6050 models and TCA9548A
 * multiplexers); an address acknowledges when i2cbus_transfer says so. Written
 * bytes reach the device at STOP or repeated START (one transfer: register pointer, then
 * data; a multiplexer keeps the last byte as its control register); read bytes come one
 * by one, all at the time of the SLA+R, like the chip's shadow registers that keep a
 * burst read consistent.
 */
#include <string.h>

#include "avr_twi.h"
#include "harness.h"
#include "sim_cycle_timers.h"
#include "sim_interrupts.h"
#include "sim_io.h"

#define R_TWBR 0xB8u
#define R_TWSR 0xB9u
#define R_TWAR 0xBAu
#define R_TWDR 0xBBu
#define R_TWCR 0xBCu
#define R_TWAMR 0xBDu

#define TWINT_ 0x80u
#define TWEA_ 0x40u
#define TWSTA_ 0x20u
#define TWSTO_ 0x10u
#define TWWC_ 0x08u
#define TWEN_ 0x04u
#define TWIE_ 0x01u

#define TWI_VECTOR 24u /* TWI_vect on the ATmega328P */
#define TXMAX 64u

enum op { OP_NONE, OP_START, OP_STOP, OP_ADDR, OP_TX, OP_RX };

static struct {
    avr_t *avr;
    avr_int_vector_t vec;
    uint8_t twcr, status, twdr, twps;
    uint8_t owned;     /* START sent, no STOP yet */
    uint8_t op;        /* operation in flight (TWINT clear), OP_NONE when idle */
    uint8_t restart;   /* the START in flight is repeated */
    uint8_t sla;       /* address byte of the current transaction */
    uint8_t acked;     /* the device acknowledged its address */
    uint8_t tx[TXMAX];
    uint8_t ntx;
    uint64_t read_us;  /* time of the SLA+R: the burst reads one sample */
    uint64_t owned_since, bus_cycles, transactions;
    /* A device holding SDA low (a transfer cut short by a reset): no START can be made
     * until it sees release_clocks SCL pulses (0 = never), driven as GPIO on PC5 while
     * the TWI is off, the usual 9-clock bus recovery. */
    uint8_t sda_held, release_clocks, clocks_seen, start_blocked, scl_low;
    avr_io_write_t portc_w, ddrc_w;
    void *portc_p, *ddrc_p;
} t;

static uint32_t scl_cycles(void)
{
    static const uint32_t prescale[4] = {1u, 4u, 16u, 64u};
    return 16u + 2u * (uint32_t)t.avr->data[R_TWBR] * prescale[t.twps & 3u];
}

static void set_owned(uint8_t owned)
{
    if (owned == t.owned) {
        return;
    }
    if (owned) {
        t.owned_since = emu_now_cycles();
        t.transactions++;
    } else {
        t.bus_cycles += emu_now_cycles() - t.owned_since;
    }
    t.owned = owned;
    emu_i2c_bus_changed(owned);
}

static void mirror(void)
{
    t.avr->data[R_TWCR] = t.twcr;
    t.avr->data[R_TWSR] = (uint8_t)(((t.twcr & TWINT_) ? t.status : 0xF8u) | (t.twps & 3u));
    t.avr->data[R_TWDR] = t.twdr;
}

static int device_acks(uint8_t addr7)
{
    return i2cbus_transfer(addr7, 0, 0, 0, 0, emu_now_us()) == 0;
}

/* Bytes written since the address phase go to the device (pointer, then data). */
static void flush_writes(void)
{
    if (t.acked && !(t.sla & 1u) && t.ntx) {
        (void)i2cbus_transfer((uint8_t)(t.sla >> 1), t.tx, t.ntx, 0, 0, emu_now_us());
    }
    t.ntx = 0;
}

static void raise_if_enabled(void)
{
    if ((t.twcr & (TWINT_ | TWIE_ | TWEN_)) == (TWINT_ | TWIE_ | TWEN_)) {
        avr_raise_interrupt(t.avr, &t.vec);
    }
}

static avr_cycle_count_t complete(struct avr_t *avr, avr_cycle_count_t when, void *param)
{
    (void)avr;
    (void)param;
    switch (t.op) {
    case OP_START:
        set_owned(1);
        t.status = t.restart ? 0x10u : 0x08u;
        break;
    case OP_STOP:
        flush_writes();
        set_owned(0);
        t.twcr &= (uint8_t)~TWSTO_; /* no TWINT after a STOP */
        t.op = OP_NONE;
        mirror();
        return 0;
    case OP_ADDR:
        t.sla = t.twdr;
        t.ntx = 0;
        t.acked = (uint8_t)device_acks((uint8_t)(t.sla >> 1));
        if (t.sla & 1u) {
            t.status = t.acked ? 0x40u : 0x48u;
            t.read_us = emu_now_us();
        } else {
            t.status = t.acked ? 0x18u : 0x20u;
        }
        break;
    case OP_TX:
        if (t.acked && t.ntx < TXMAX) {
            t.tx[t.ntx++] = t.twdr;
        }
        t.status = t.acked ? 0x28u : 0x30u;
        break;
    case OP_RX: {
        uint8_t b = 0xFFu; /* nobody drives SDA: the pull-ups read ones */
        if (t.acked) {
            (void)i2cbus_transfer((uint8_t)(t.sla >> 1), 0, 0, &b, 1, t.read_us);
        }
        t.twdr = b;
        t.status = (t.twcr & TWEA_) ? 0x50u : 0x58u;
        break;
    }
    default:
        return 0;
    }
    t.op = OP_NONE;
    t.twcr |= TWINT_;
    mirror();
    raise_if_enabled();
    (void)when;
    return 0;
}

static void start_op(uint8_t op, uint32_t bits)
{
    t.op = op;
    if (op == OP_START && t.sda_held) {
        t.start_blocked = 1; /* the bus is not free: the START waits */
        return;
    }
    avr_cycle_timer_register(t.avr, (avr_cycle_count_t)bits * scl_cycles(), complete, 0);
}

/* TWINT was cleared by a write of one: the hardware acts on TWSTA/TWSTO/TWDR. */
static void act(void)
{
    if (t.twcr & TWSTO_) {
        if (t.owned) {
            if (t.twcr & TWSTA_) {
                /* STOP then START: the STOP is on the bus at once, the START follows. */
                flush_writes();
                set_owned(0);
                t.twcr &= (uint8_t)~TWSTO_;
                t.restart = 0;
                start_op(OP_START, 2u);
                return;
            }
            start_op(OP_STOP, 1u);
            return;
        }
        t.twcr &= (uint8_t)~TWSTO_; /* nothing to stop */
        if (!(t.twcr & TWSTA_)) {
            return;
        }
    }
    if (t.twcr & TWSTA_) {
        flush_writes();
        t.restart = t.owned;
        start_op(OP_START, 1u);
        return;
    }
    if (!t.owned) {
        return; /* TWINT cleared without a START: the bus stays idle */
    }
    switch (t.status) {
    case 0x08u:
    case 0x10u:
        start_op(OP_ADDR, 9u);
        break;
    case 0x18u:
    case 0x20u:
    case 0x28u:
    case 0x30u:
        start_op(OP_TX, 9u);
        break;
    case 0x40u:
    case 0x50u:
        start_op(OP_RX, 9u);
        break;
    default:
        break; /* 0x48/0x58: only STOP or repeated START are meaningful */
    }
}

static void write_twcr(struct avr_t *avr, avr_io_addr_t addr, uint8_t v, void *param)
{
    uint8_t old = t.twcr;
    (void)avr;
    (void)addr;
    (void)param;
    if (!(v & TWEN_)) {
        /* TWI off: transmissions end, the pins go back to the port (datasheet §22.9.2). */
        avr_cycle_timer_cancel(t.avr, complete, 0);
        t.op = OP_NONE;
        t.ntx = 0;
        t.acked = 0;
        set_owned(0);
        t.twcr = (uint8_t)((v & (TWEA_ | TWSTA_ | TWSTO_ | TWIE_)) | ((v & TWINT_) ? 0u : (old & TWINT_)));
        t.twcr &= (uint8_t)~(TWSTO_ | TWSTA_ | TWEA_);
        t.status = 0xF8u;
        mirror();
        return;
    }
    t.twcr = (uint8_t)((v & (TWEA_ | TWSTA_ | TWSTO_ | TWEN_ | TWIE_)) | (old & TWWC_));
    if (v & TWINT_) {
        avr_clear_interrupt(t.avr, &t.vec);
        if (t.op == OP_NONE) {
            act();
        }
        mirror();
    } else {
        t.twcr |= (uint8_t)(old & TWINT_);
        mirror();
        raise_if_enabled();
    }
}

static uint8_t read_twcr(struct avr_t *avr, avr_io_addr_t addr, void *param)
{
    (void)avr;
    (void)addr;
    (void)param;
    return t.twcr;
}

static void write_twdr(struct avr_t *avr, avr_io_addr_t addr, uint8_t v, void *param)
{
    (void)avr;
    (void)addr;
    (void)param;
    if (t.twcr & TWINT_) {
        t.twdr = v;
        t.twcr &= (uint8_t)~TWWC_;
    } else {
        t.twcr |= TWWC_; /* write collision: TWDR keeps its byte */
    }
    mirror();
}

static uint8_t read_twdr(struct avr_t *avr, avr_io_addr_t addr, void *param)
{
    (void)avr;
    (void)addr;
    (void)param;
    return t.twdr;
}

static void write_twsr(struct avr_t *avr, avr_io_addr_t addr, uint8_t v, void *param)
{
    (void)avr;
    (void)addr;
    (void)param;
    t.twps = (uint8_t)(v & 3u); /* only the prescaler bits are writable */
    mirror();
}

static uint8_t read_twsr(struct avr_t *avr, avr_io_addr_t addr, void *param)
{
    (void)avr;
    (void)addr;
    (void)param;
    return (uint8_t)(((t.twcr & TWINT_) ? t.status : 0xF8u) | (t.twps & 3u));
}

static void write_plain(struct avr_t *avr, avr_io_addr_t addr, uint8_t v, void *param)
{
    (void)param;
    avr->data[addr] = v;
}

static uint8_t read_plain(struct avr_t *avr, avr_io_addr_t addr, void *param)
{
    (void)param;
    return avr->data[addr];
}

static void release_sda(void)
{
    t.sda_held = 0;
    if (t.start_blocked && t.op == OP_START) {
        t.start_blocked = 0;
        start_op(OP_START, 1u);
    }
}

/* SCL as a GPIO (PC5): low when driven low as an output, else pulled up. */
static void scl_pin_changed(struct avr_t *avr)
{
    uint8_t low = (uint8_t)((avr->data[0x27] & 0x20u) && !(avr->data[0x28] & 0x20u));
    if (t.scl_low && !low && !(t.twcr & TWEN_) && t.sda_held && t.release_clocks) {
        if (++t.clocks_seen >= t.release_clocks) {
            release_sda();
        }
    }
    t.scl_low = low;
}

static void write_portc(struct avr_t *avr, avr_io_addr_t addr, uint8_t v, void *param)
{
    (void)param;
    if (t.portc_w) {
        t.portc_w(avr, addr, v, t.portc_p);
    } else {
        avr->data[addr] = v;
    }
    scl_pin_changed(avr);
}

static void write_ddrc(struct avr_t *avr, avr_io_addr_t addr, uint8_t v, void *param)
{
    (void)param;
    if (t.ddrc_w) {
        t.ddrc_w(avr, addr, v, t.ddrc_p);
    } else {
        avr->data[addr] = v;
    }
    scl_pin_changed(avr);
}

/* While TWINT and TWIE stay set the interrupt is taken again after RETI (level). */
static void vector_running(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)param;
    if (value == 0u) {
        raise_if_enabled();
    }
}

static void own(avr_t *avr, uint16_t reg, avr_io_write_t w, avr_io_read_t r)
{
    avr_io_addr_t a = AVR_DATA_TO_IO(reg);
    avr->io[a].w.c = w;
    avr->io[a].w.param = 0;
    avr->io[a].r.c = r;
    avr->io[a].r.param = 0;
}

void twi_attach(avr_t *avr)
{
    memset(&t, 0, sizeof t);
    t.avr = avr;
    own(avr, R_TWBR, write_plain, read_plain);
    own(avr, R_TWSR, write_twsr, read_twsr);
    own(avr, R_TWAR, write_plain, read_plain);
    own(avr, R_TWDR, write_twdr, read_twdr);
    own(avr, R_TWCR, write_twcr, read_twcr);
    own(avr, R_TWAMR, write_plain, read_plain);
    t.portc_w = avr->io[AVR_DATA_TO_IO(0x28)].w.c;
    t.portc_p = avr->io[AVR_DATA_TO_IO(0x28)].w.param;
    avr->io[AVR_DATA_TO_IO(0x28)].w.c = write_portc;
    avr->io[AVR_DATA_TO_IO(0x28)].w.param = 0;
    t.ddrc_w = avr->io[AVR_DATA_TO_IO(0x27)].w.c;
    t.ddrc_p = avr->io[AVR_DATA_TO_IO(0x27)].w.param;
    avr->io[AVR_DATA_TO_IO(0x27)].w.c = write_ddrc;
    avr->io[AVR_DATA_TO_IO(0x27)].w.param = 0;
    t.vec.vector = TWI_VECTOR;
    t.vec.enable.reg = R_TWCR;
    t.vec.enable.bit = 0;
    t.vec.enable.mask = 1;
    avr_register_vector(avr, &t.vec);
    avr_irq_register_notify(t.vec.irq + AVR_INT_IRQ_RUNNING, vector_running, 0);
    twi_reset();
}

void twi_reset(void)
{
    avr_t *avr = t.avr;
    avr_cycle_timer_cancel(avr, complete, 0);
    t.twcr = 0;
    t.status = 0xF8u;
    t.twdr = 0xFFu;
    t.twps = 0;
    t.owned = 0;
    t.op = OP_NONE;
    t.ntx = 0;
    t.acked = 0;
    t.start_blocked = 0;
    t.clocks_seen = 0;
    t.scl_low = 0;
    t.bus_cycles = 0;
    t.transactions = 0;
    t.vec.pending = 0;
    avr->data[R_TWBR] = 0;
    avr->data[R_TWAR] = 0xFEu;
    avr->data[R_TWAMR] = 0;
    mirror();
}

uint64_t twi_transactions(void)
{
    return t.transactions;
}

uint64_t twi_bus_cycles(void)
{
    return t.bus_cycles + (t.owned ? emu_now_cycles() - t.owned_since : 0u);
}

int twi_bus_owned(void)
{
    return t.owned;
}

void twi_hold_sda(int held, uint8_t release_clocks)
{
    t.clocks_seen = 0;
    t.release_clocks = release_clocks;
    if (held) {
        t.sda_held = 1;
    } else {
        release_sda();
    }
}
