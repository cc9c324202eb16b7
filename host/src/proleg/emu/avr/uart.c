/* uart.c - the avr-emu board's UART0 link to the host: two byte queues and the wire's timing.
 *
 * Contract. uart_open gives the clock and the host's baud rate, uart_attach hooks a new
 * core's UART0 (after avr_init), uart_power_on empties the queues and the loss counters,
 * uart_mcu_reset restarts delivery after every MCU reset; the host's side is the emu_uart_*
 * ABI below. Nothing here knows the rest of the board.
 *
 * Board -> host: every byte the firmware writes to UDR0 is queued for the host the moment
 * the core writes it; simavr then paces UDRE at the frame time. simavr 1.6 counts 11 bits
 * per frame (a parity bit even with parity off); the frame time is set again after each
 * write of UBRR0L, UCSR0A or UCSR0C from the registers, as the chip does: (UBRR0 + 1) ·
 * (U2X0 ? 8 : 16) cycles per bit, 1 start + data + parity (only when UPM0 is set) + stop
 * bits. Host -> board: bytes wait in a host queue and reach the receiver one frame (10 bits
 * at the host's baud rate) apart, as on the wire; a frame that arrives while the receiver
 * holds three unread characters (two in UDR0's FIFO, one in the shift register) overwrites
 * the shift register's (data overrun, as on the chip), and bytes sent while the receiver is
 * disabled are lost.
 */
#include <string.h>

#include "avr_uart.h"
#include "harness.h"
#include "sim_cycle_timers.h"
#include "sim_io.h"
#include "sim_irq.h"

#define EMU_API __attribute__((visibility("default")))

#define R_UCSR0A 0xC0u
#define R_UCSR0B 0xC1u
#define R_UCSR0C 0xC2u
#define R_UBRR0L 0xC4u
#define R_UBRR0H 0xC5u
#define RXEN0_ 0x10u
#define UCSZ02_ 0x04u
#define U2X0_ 0x02u

#define RXQ_SIZE 4096u
#define HOSTQ_SIZE 65536u

typedef struct {
    uint8_t *buf;
    uint32_t cap, head, count;
} fifo_t;

static uint8_t rxq_mem[RXQ_SIZE], hostq_mem[HOSTQ_SIZE];

static struct {
    uint32_t freq, host_baud;
    avr_uart_t *uart;
    avr_irq_t *uart_irq;
    fifo_t rxq, hostq;
    uint8_t rx_pump_on;
    uint64_t rx_t0, rx_n;
    uint32_t rx_overruns, rx_receiver_off, rxq_dropped, hostq_dropped;
    emu_wrapped_t w_ubrr0l, w_ucsr0a, w_ucsr0c;
} U;

static uint32_t fifo_put(fifo_t *f, const uint8_t *data, uint32_t n)
{
    uint32_t i;
    for (i = 0; i < n && f->count < f->cap; i++) {
        f->buf[(f->head + f->count) % f->cap] = data[i];
        f->count++;
    }
    return i;
}

static int fifo_get(fifo_t *f)
{
    uint8_t b;
    if (f->count == 0u) {
        return -1;
    }
    b = f->buf[f->head];
    f->head = (f->head + 1u) % f->cap;
    f->count--;
    return b;
}

static void fix_frame_time(struct avr_t *avr)
{
    static const uint8_t databits[8] = {5, 6, 7, 8, 8, 8, 8, 9};
    uint8_t *d = avr->data;
    uint32_t ubrr = d[R_UBRR0L] | ((uint32_t)(d[R_UBRR0H] & 0x0Fu) << 8);
    uint32_t per_bit = (ubrr + 1u) * ((d[R_UCSR0A] & U2X0_) ? 8u : 16u);
    uint32_t ucsz = ((d[R_UCSR0C] >> 1) & 3u) | ((d[R_UCSR0B] & UCSZ02_) ? 4u : 0u);
    uint32_t parity = ((d[R_UCSR0C] >> 4) & 3u) ? 1u : 0u;
    uint32_t stop = (d[R_UCSR0C] & 0x08u) ? 2u : 1u;
    if (U.uart) {
        U.uart->cycles_per_byte = per_bit * (1u + databits[ucsz] + parity + stop);
    }
}

static void w_ubrr0l(struct avr_t *avr, avr_io_addr_t addr, uint8_t v, void *param)
{
    (void)param;
    emu_call_wrapped(&U.w_ubrr0l, avr, addr, v);
    fix_frame_time(avr);
}

static void w_ucsr0a(struct avr_t *avr, avr_io_addr_t addr, uint8_t v, void *param)
{
    (void)param;
    emu_call_wrapped(&U.w_ucsr0a, avr, addr, v);
    fix_frame_time(avr);
}

static void w_ucsr0c(struct avr_t *avr, avr_io_addr_t addr, uint8_t v, void *param)
{
    (void)param;
    emu_call_wrapped(&U.w_ucsr0c, avr, addr, v);
    fix_frame_time(avr);
}

static void on_uart_out(struct avr_irq_t *irq, uint32_t value, void *param)
{
    uint8_t b = (uint8_t)value;
    (void)irq;
    (void)param;
    if (fifo_put(&U.hostq, &b, 1) != 1u) {
        U.hostq_dropped++;
    }
}

static uint64_t host_frame_end(uint64_t n)
{
    return U.rx_t0 + (n * 10u * (uint64_t)U.freq + U.host_baud / 2u) / U.host_baud;
}

/* Characters the receiver holds that the firmware has not read (simavr's input FIFO). */
static uint32_t rx_unread(void)
{
    const uart_fifo_t *f = &U.uart->input;
    return ((uint32_t)f->write + uart_fifo_fifo_size - f->read) & (uart_fifo_fifo_size - 1u);
}

/* One byte from the host reaches the receiver (its stop bit just arrived). */
static void deliver_rx_byte(void)
{
    int c = fifo_get(&U.rxq);
    if (c < 0) {
        return;
    }
    if (!(emu_core()->data[R_UCSR0B] & RXEN0_)) {
        U.rx_receiver_off++;
    } else if (rx_unread() >= 3u) {
        /* UDR0's two-character FIFO and the shift register are full: the new frame
         * overwrites the shift register (data overrun, datasheet §20.7.4). */
        uart_fifo_t *f = &U.uart->input;
        f->buffer[(f->write + uart_fifo_fifo_size - 1u) & (uart_fifo_fifo_size - 1u)] = (uint16_t)c;
        U.rx_overruns++;
    } else {
        avr_raise_irq(U.uart_irq + UART_IRQ_INPUT, (uint32_t)c);
    }
}

static avr_cycle_count_t rx_pump(struct avr_t *avr, avr_cycle_count_t when, void *param)
{
    (void)avr;
    (void)when;
    (void)param;
    deliver_rx_byte();
    U.rx_n++;
    if (U.rxq.count == 0u) {
        U.rx_pump_on = 0;
        return 0;
    }
    return emu_power_on_cycle() + host_frame_end(U.rx_n + 1u); /* byte n + 1's stop bit */
}

static void rx_pump_start(void)
{
    if (U.rx_pump_on || U.rxq.count == 0u) {
        return;
    }
    U.rx_pump_on = 1;
    U.rx_t0 = emu_now_cycles();
    U.rx_n = 0;
    avr_cycle_timer_register(emu_core(), host_frame_end(1) - U.rx_t0, rx_pump, 0);
}

/* -- the board's side --------------------------------------------------------------- */

void uart_open(uint32_t freq, uint32_t host_baud)
{
    U.freq = freq;
    U.host_baud = host_baud;
    U.rxq.buf = rxq_mem;
    U.rxq.cap = RXQ_SIZE;
    U.hostq.buf = hostq_mem;
    U.hostq.cap = HOSTQ_SIZE;
}

int uart_attach(avr_t *avr)
{
    uint32_t flags = 0;
    U.uart = 0;
    for (avr_io_t *p = avr->io_port; p; p = p->next) {
        if (p->kind && strcmp(p->kind, "uart") == 0 && ((avr_uart_t *)p)->name == '0') {
            U.uart = (avr_uart_t *)p;
        }
    }
    if (!U.uart) {
        return -1;
    }
    U.uart_irq = avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), 0);
    avr_ioctl(avr, AVR_IOCTL_UART_SET_FLAGS('0'), &flags); /* no usleep, no console echo */
    avr_irq_register_notify(U.uart_irq + UART_IRQ_OUTPUT, on_uart_out, 0);
    emu_wrap_write(avr, R_UBRR0L, &U.w_ubrr0l, w_ubrr0l);
    emu_wrap_write(avr, R_UCSR0A, &U.w_ucsr0a, w_ucsr0a);
    emu_wrap_write(avr, R_UCSR0C, &U.w_ucsr0c, w_ucsr0c);
    return 0;
}

void uart_power_on(void)
{
    U.rxq.head = U.rxq.count = 0;
    U.hostq.head = U.hostq.count = 0;
    U.rx_overruns = U.rx_receiver_off = U.rxq_dropped = U.hostq_dropped = 0;
}

void uart_mcu_reset(void)
{
    U.rx_pump_on = 0;
    rx_pump_start();
}

/* -- the ABI ------------------------------------------------------------------------ */

EMU_API void emu_uart_write(const uint8_t *data, uint32_t n)
{
    U.rxq_dropped += n - fifo_put(&U.rxq, data, n);
    rx_pump_start();
}

EMU_API uint32_t emu_uart_read(uint8_t *out, uint32_t cap)
{
    uint32_t n = 0;
    while (n < cap && U.hostq.count > 0u) {
        out[n++] = (uint8_t)fifo_get(&U.hostq);
    }
    return n;
}

/* Host -> board bytes lost: [0] receiver overrun, [1] receiver disabled, [2] host queue
 * full; board -> host: [3] host queue full. */
EMU_API void emu_uart_losses(uint32_t out[4])
{
    out[0] = U.rx_overruns;
    out[1] = U.rx_receiver_off;
    out[2] = U.rxq_dropped;
    out[3] = U.hostq_dropped;
}

EMU_API uint64_t emu_uart_cycles_per_byte(void)
{
    return U.uart->cycles_per_byte;
}
