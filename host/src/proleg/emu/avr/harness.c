/* harness.c - the avr-emu board's simavr core, UART link, PWM read-out and tick markers.
 * See harness.h; the Python side is proleg/emu/avr/board.py (ctypes), the ABI is the
 * list of EMU_API functions below.
 *
 * UART0. Board -> host: every byte the firmware writes to UDR0 is queued for the host
 * the moment the core writes it; simavr then paces UDRE at the frame time. simavr 1.6
 * counts 11 bits per frame (a parity bit even with parity off); the frame time is set
 * again after each write of UBRR0L, UCSR0A or UCSR0C from the registers, as the chip
 * does: (UBRR0 + 1) · (U2X0 ? 8 : 16) cycles per bit, 1 start + data + parity (only when
 * UPM0 is set) + stop bits. Host -> board: bytes wait in a host queue and reach the
 * receiver one frame (10 bits at the host's baud rate) apart, as on the wire; a frame that
 * arrives while the receiver holds three unread characters (two in UDR0's FIFO, one in
 * the shift register) overwrites the shift register's (data overrun, as on the chip),
 * and bytes sent while the receiver is disabled are lost.
 *
 * PWM. The duty of an output-compare pin is computed from the timer registers (waveform
 * mode, TOP, OCRnx, COMnx) and, when the compare output is disconnected, from the port
 * pin (DDR and PORT), so it does not depend on simavr's pin waveform (which is wrong for
 * Timer1 mode 14, fast PWM with TOP = ICR1: simavr 1.6 runs it as phase-correct).
 *
 * Tick markers. A control tick's busy time runs from the moment the firmware leaves its
 * tick wait to the moment it enters it again. Firmware that writes GPIOR0 (bit 0 = 1 at
 * the start of the tick's work, 0 at its end) is measured from those writes; otherwise
 * Python gives two program addresses found in the ELF (the first instruction after the
 * wait and the first instruction of the wait): reaching one starts, the other ends the
 * busy time. Each completed tick is recorded: start, busy cycles, and the cycles the I2C
 * bus was owned (START..STOP) during the busy time. The lowest stack pointer seen is kept.
 *
 * Skips. simavr 1.6 decides whether the instruction after a skip (CPSE, SBRC, SBRS, SBIC,
 * SBIS) is one or two words with the mask 0xFC0F, so it also takes ADIW/SBIW with some
 * operands (0x9[46]xF and 0x9[46]xE, e.g. adiw r24,0x1f = 0x964F), and a few other
 * opcodes, for LDS/STS/JMP/CALL and skips two words instead of one: the instruction after
 * the one-word one is skipped too (avr-gcc emits `cpse r15,r1; adiw r24,0x1f` for
 * `if (x) i += 31;`; it made the Nano start every gait of a 3-limb robot with 0 steps).
 * The firmware's flash is scanned at load for skips followed by such a one-word
 * instruction; the run loop executes those skips itself (AVR instruction set manual:
 * 1 cycle if the condition is false, 2 if it skips a one-word instruction).
 */
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "avr_eeprom.h"
#include "avr_ioport.h"
#include "avr_uart.h"
#include "harness.h"
#include "sim_cycle_timers.h"
#include "sim_elf.h"
#include "sim_interrupts.h"
#include "sim_io.h"
#include "sim_irq.h"
#include "sim_mpu6050.h"

#define EMU_API __attribute__((visibility("default")))

#define R_UCSR0A 0xC0u
#define R_UCSR0B 0xC1u
#define R_UCSR0C 0xC2u
#define R_UBRR0L 0xC4u
#define R_UBRR0H 0xC5u
#define R_GPIOR0 0x3Eu
#define R_MCUSR 0x54u
#define RXEN0_ 0x10u
#define UCSZ02_ 0x04u
#define U2X0_ 0x02u

#define RXQ_SIZE 4096u
#define HOSTQ_SIZE 65536u
#define TICKS_SIZE 16384u
#define MAX_PWM 8u
#define FLASH_WORDS 16384u /* 32 KB of flash */
#define NO_PC 0xFFFFFFFFu

/* Output-compare pins, as emu_set_pwm_map numbers them. */
enum { OC0A, OC0B, OC1A, OC1B, OC2A, OC2B, OC_COUNT };

typedef struct {
    uint8_t *buf;
    uint32_t cap, head, count;
} fifo_t;

typedef struct {
    avr_io_write_t c;
    void *param;
} wrapped_t;

typedef struct {
    uint64_t start;
    uint32_t busy, i2c;
} tick_rec_t;

static uint8_t rxq_mem[RXQ_SIZE], hostq_mem[HOSTQ_SIZE];
static uint64_t prof_cycles[FLASH_WORDS]; /* cycles spent per instruction address */
static uint8_t bad_skip[FLASH_WORDS / 8u]; /* word addresses of skips simavr 1.6 gets wrong */
static uint8_t profiling;

static struct {
    avr_t *avr;
    elf_firmware_t fw;
    uint32_t freq, host_baud;
    uint64_t cycle0; /* avr->cycle at the last power-on */
    avr_uart_t *uart;
    avr_irq_t *uart_irq;
    avr_io_t io;     /* our module: its reset hook runs on every MCU reset */
    fifo_t rxq, hostq;
    uint8_t rx_pump_on;
    uint64_t rx_t0, rx_n;
    uint32_t rx_overruns, rx_receiver_off, rxq_dropped, hostq_dropped;
    uint8_t pwm_map[MAX_PWM];
    uint8_t n_pwm;
    wrapped_t w_ubrr0l, w_ucsr0a, w_ucsr0c, w_gpior0;
    /* tick markers */
    uint32_t mark_start, mark_end;
    uint8_t gpio_mode;
    uint8_t busy, i2c_owned;
    uint64_t busy_since, ov_last, ov_acc;
    tick_rec_t ticks[TICKS_SIZE];
    uint32_t t_head, t_count;
    uint64_t ticks_total, ticks_lost;
    uint16_t sp_min;
    uint64_t mcu_resets;
} E;

/* ------------------------------------------------------------------ small things */

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

static void silent_logger(struct avr_t *avr, const int level, const char *format, va_list ap)
{
    (void)avr;
    (void)level;
    (void)format;
    (void)ap;
}

static void no_sleep(struct avr_t *avr, avr_cycle_count_t how_long)
{
    (void)avr;
    (void)how_long; /* virtual time: never wait for the wall clock */
}

uint64_t emu_now_cycles(void)
{
    return E.avr->cycle - E.cycle0;
}

avr_t *emu_core(void)
{
    return E.avr;
}

uint64_t emu_now_us(void)
{
    return emu_now_cycles() * 1000000u / E.freq;
}

/* ------------------------------------------------------------------ tick markers */

static void overlap_account(void)
{
    uint64_t now = emu_now_cycles();
    if (E.busy && E.i2c_owned) {
        E.ov_acc += now - E.ov_last;
    }
    E.ov_last = now;
}

void emu_i2c_bus_changed(int owned)
{
    overlap_account();
    E.i2c_owned = (uint8_t)(owned != 0);
}

static void busy_begin(void)
{
    overlap_account();
    E.busy = 1;
    E.busy_since = emu_now_cycles();
    E.ov_acc = 0;
}

static void busy_end(void)
{
    tick_rec_t *r;
    overlap_account();
    if (!E.busy) {
        return;
    }
    E.busy = 0;
    if (E.t_count == TICKS_SIZE) {
        E.t_head = (E.t_head + 1u) % TICKS_SIZE;
        E.t_count--;
        E.ticks_lost++;
    }
    r = &E.ticks[(E.t_head + E.t_count) % TICKS_SIZE];
    r->start = E.busy_since;
    r->busy = (uint32_t)(emu_now_cycles() - E.busy_since);
    r->i2c = (uint32_t)E.ov_acc;
    E.t_count++;
    E.ticks_total++;
}

/* ------------------------------------------------------------------ UART0 */

static void call_wrapped(const wrapped_t *w, struct avr_t *avr, avr_io_addr_t addr, uint8_t v)
{
    if (w->c) {
        w->c(avr, addr, v, w->param);
    } else {
        avr->data[addr] = v;
    }
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
    if (E.uart) {
        E.uart->cycles_per_byte = per_bit * (1u + databits[ucsz] + parity + stop);
    }
}

static void w_ubrr0l(struct avr_t *avr, avr_io_addr_t addr, uint8_t v, void *param)
{
    (void)param;
    call_wrapped(&E.w_ubrr0l, avr, addr, v);
    fix_frame_time(avr);
}

static void w_ucsr0a(struct avr_t *avr, avr_io_addr_t addr, uint8_t v, void *param)
{
    (void)param;
    call_wrapped(&E.w_ucsr0a, avr, addr, v);
    fix_frame_time(avr);
}

static void w_ucsr0c(struct avr_t *avr, avr_io_addr_t addr, uint8_t v, void *param)
{
    (void)param;
    call_wrapped(&E.w_ucsr0c, avr, addr, v);
    fix_frame_time(avr);
}

static void w_gpior0(struct avr_t *avr, avr_io_addr_t addr, uint8_t v, void *param)
{
    uint8_t was = avr->data[addr];
    (void)param;
    call_wrapped(&E.w_gpior0, avr, addr, v);
    E.gpio_mode = 1;
    if ((v & 1u) && !(was & 1u)) {
        busy_begin();
    } else if (!(v & 1u) && (was & 1u)) {
        busy_end();
    }
}

static void wrap(avr_t *avr, uint16_t reg, wrapped_t *save, avr_io_write_t w)
{
    avr_io_addr_t a = AVR_DATA_TO_IO(reg);
    save->c = avr->io[a].w.c;
    save->param = avr->io[a].w.param;
    avr->io[a].w.c = w;
    avr->io[a].w.param = 0;
}

static void on_uart_out(struct avr_irq_t *irq, uint32_t value, void *param)
{
    uint8_t b = (uint8_t)value;
    (void)irq;
    (void)param;
    if (fifo_put(&E.hostq, &b, 1) != 1u) {
        E.hostq_dropped++;
    }
}

static uint64_t host_frame_end(uint64_t n)
{
    return E.rx_t0 + (n * 10u * (uint64_t)E.freq + E.host_baud / 2u) / E.host_baud;
}

/* Characters the receiver holds that the firmware has not read (simavr's input FIFO). */
static uint32_t rx_unread(void)
{
    const uart_fifo_t *f = &E.uart->input;
    return ((uint32_t)f->write + uart_fifo_fifo_size - f->read) & (uart_fifo_fifo_size - 1u);
}

/* One byte from the host reaches the receiver (its stop bit just arrived). */
static void deliver_rx_byte(void)
{
    int c = fifo_get(&E.rxq);
    if (c < 0) {
        return;
    }
    if (!(E.avr->data[R_UCSR0B] & RXEN0_)) {
        E.rx_receiver_off++;
    } else if (rx_unread() >= 3u) {
        /* UDR0's two-character FIFO and the shift register are full: the new frame
         * overwrites the shift register (data overrun, datasheet §20.7.4). */
        uart_fifo_t *f = &E.uart->input;
        f->buffer[(f->write + uart_fifo_fifo_size - 1u) & (uart_fifo_fifo_size - 1u)] = (uint16_t)c;
        E.rx_overruns++;
    } else {
        avr_raise_irq(E.uart_irq + UART_IRQ_INPUT, (uint32_t)c);
    }
}

static avr_cycle_count_t rx_pump(struct avr_t *avr, avr_cycle_count_t when, void *param)
{
    (void)avr;
    (void)when;
    (void)param;
    deliver_rx_byte();
    E.rx_n++;
    if (E.rxq.count == 0u) {
        E.rx_pump_on = 0;
        return 0;
    }
    return E.cycle0 + host_frame_end(E.rx_n + 1u); /* byte n + 1's stop bit */
}

static void rx_pump_start(void)
{
    if (E.rx_pump_on || E.rxq.count == 0u) {
        return;
    }
    E.rx_pump_on = 1;
    E.rx_t0 = emu_now_cycles();
    E.rx_n = 0;
    avr_cycle_timer_register(E.avr, host_frame_end(1) - E.rx_t0, rx_pump, 0);
}

/* ------------------------------------------------------------------ PWM */

static uint16_t u16(const uint8_t *d, uint16_t lo)
{
    return (uint16_t)(d[lo] | (d[lo + 1u] << 8));
}

/* Duty of an output-compare pin in permyriad, from the registers. */
static uint16_t oc_duty(uint8_t oc)
{
    static const uint8_t port_reg[OC_COUNT] = {0x2Bu, 0x2Bu, 0x25u, 0x25u, 0x25u, 0x2Bu};
    static const uint8_t pin_bit[OC_COUNT] = {6u, 5u, 1u, 2u, 3u, 3u};
    const uint8_t *d = E.avr->data;
    uint8_t port = port_reg[oc], bit = pin_bit[oc];
    uint8_t com, wgm, cs, fast;
    uint32_t top, ocr;
    uint64_t duty;
    if (!(d[port - 1u] & (1u << bit))) {
        return 0; /* pin is an input: the gate pull-down holds the MOSFET off */
    }
    switch (oc) {
    case OC1A:
    case OC1B:
        com = (uint8_t)((d[0x80] >> (oc == OC1A ? 6 : 4)) & 3u);
        wgm = (uint8_t)((d[0x80] & 3u) | ((d[0x81] >> 1) & 0x0Cu));
        cs = d[0x81] & 7u;
        ocr = u16(d, oc == OC1A ? 0x88u : 0x8Au);
        switch (wgm) {
        case 1: top = 0xFFu; fast = 0; break;
        case 2: top = 0x1FFu; fast = 0; break;
        case 3: top = 0x3FFu; fast = 0; break;
        case 5: top = 0xFFu; fast = 1; break;
        case 6: top = 0x1FFu; fast = 1; break;
        case 7: top = 0x3FFu; fast = 1; break;
        case 8: case 10: top = u16(d, 0x86u); fast = 0; break;
        case 9: case 11: top = u16(d, 0x88u); fast = 0; break;
        case 14: top = u16(d, 0x86u); fast = 1; break;
        case 15: top = u16(d, 0x88u); fast = 1; break;
        default: com = 0; top = 0; fast = 0; break; /* normal / CTC: no PWM */
        }
        if ((wgm == 9 || wgm == 11 || wgm == 15) && oc == OC1A) {
            com = 0; /* OCR1A is TOP: OC1A only toggles (not a duty) */
        }
        break;
    default: {
        uint8_t a = (oc <= OC0B) ? 0x44u : 0xB0u; /* TCCRnA; TCCRnB = +1, OCRnA = +3, OCRnB = +4 */
        uint8_t is_a = (oc == OC0A || oc == OC2A);
        com = (uint8_t)((d[a] >> (is_a ? 6 : 4)) & 3u);
        wgm = (uint8_t)((d[a] & 3u) | ((d[a + 1u] >> 1) & 4u));
        cs = d[a + 1u] & 7u;
        ocr = d[a + (is_a ? 3u : 4u)];
        switch (wgm) {
        case 1: top = 0xFFu; fast = 0; break;
        case 3: top = 0xFFu; fast = 1; break;
        case 5: top = d[a + 3u]; fast = 0; break;
        case 7: top = d[a + 3u]; fast = 1; break;
        default: com = 0; top = 0; fast = 0; break;
        }
        if ((wgm == 5 || wgm == 7) && is_a) {
            com = 0;
        }
        break;
    }
    }
    if (com < 2u || cs == 0u) {
        /* Compare output disconnected (or toggle-only, or timer stopped): the port bit. */
        return (d[port] & (1u << bit)) ? 10000u : 0u;
    }
    if (fast) {
        duty = ocr >= top ? 10000u : ((uint64_t)(ocr + 1u) * 10000u + (top + 1u) / 2u) / (top + 1u);
    } else {
        duty = top == 0u ? 0u : (ocr >= top ? 10000u : ((uint64_t)ocr * 10000u + top / 2u) / top);
    }
    return (uint16_t)(com == 3u ? 10000u - duty : duty);
}

/* ------------------------------------------------------------------ reset */

/* Every MCU reset (power-on, watchdog, ...): the peripherals we own start again. */
static void on_mcu_reset(struct avr_io_t *io)
{
    (void)io;
    twi_reset();
    E.rx_pump_on = 0;
    E.busy = 0;
    E.i2c_owned = 0;
    E.mcu_resets++;
    rx_pump_start();
}

/* -- skips (see the top) ------------------------------------------------------------ */

static uint16_t flash_word(const avr_t *avr, uint32_t w)
{
    return (uint16_t)(avr->flash[2u * w] | (avr->flash[2u * w + 1u] << 8));
}

static int is_skip(uint16_t o)
{
    return (o & 0xFC00u) == 0x1000u /* CPSE */ || (o & 0xFC08u) == 0xFC00u /* SBRC, SBRS */ ||
           (o & 0xFD00u) == 0x9900u /* SBIC, SBIS */;
}

/* simavr 1.6's sim_core.c _avr_is_instruction_32_bits, and the instruction set's truth. */
static int simavr_says_two_words(uint16_t o)
{
    uint16_t m = (uint16_t)(o & 0xFC0Fu);
    return m == 0x9200u || m == 0x9000u || m == 0x940Cu || m == 0x940Du || m == 0x940Eu || m == 0x940Fu;
}

static int is_two_words(uint16_t o)
{
    return (o & 0xFE0Fu) == 0x9000u /* LDS */ || (o & 0xFE0Fu) == 0x9200u /* STS */ ||
           (o & 0xFE0Eu) == 0x940Cu /* JMP */ || (o & 0xFE0Eu) == 0x940Eu /* CALL */;
}

static void scan_skips(const avr_t *avr)
{
    uint32_t w, words = avr->flashend + 1u < 2u * FLASH_WORDS ? (avr->flashend + 1u) / 2u : FLASH_WORDS;
    memset(bad_skip, 0, sizeof bad_skip);
    for (w = 0; w + 1u < words; w++) {
        uint16_t next = flash_word(avr, w + 1u);
        if (is_skip(flash_word(avr, w)) && simavr_says_two_words(next) && !is_two_words(next)) {
            bad_skip[w >> 3] = (uint8_t)(bad_skip[w >> 3] | (1u << (w & 7u)));
        }
    }
}

static int at_bad_skip(uint32_t pc)
{
    uint32_t w = (pc >> 1) & (FLASH_WORDS - 1u);
    return (bad_skip[w >> 3] >> (w & 7u)) & 1u;
}

/* Execute the skip at pc whose next instruction is one word (only from at_bad_skip). */
static void run_skip(avr_t *avr)
{
    uint16_t o = flash_word(avr, avr->pc >> 1);
    uint8_t d = (uint8_t)((o >> 4) & 0x1Fu), b = (uint8_t)(o & 7u);
    int skip;
    if ((o & 0xFC00u) == 0x1000u) { /* CPSE Rd, Rr */
        skip = avr->data[d] == avr->data[(o & 0x0Fu) | ((o >> 5) & 0x10u)];
    } else if ((o & 0xFC08u) == 0xFC00u) { /* SBRC / SBRS Rr, b */
        skip = ((avr->data[d] >> b) & 1u) == ((o >> 9) & 1u);
    } else { /* SBIC / SBIS A, b: I/O address A = data address A + 0x20 */
        uint8_t v = avr_core_watch_read(avr, (uint16_t)(((o >> 3) & 0x1Fu) + 0x20u));
        skip = ((v >> b) & 1u) == ((o >> 9) & 1u);
    }
    avr->pc += skip ? 4u : 2u;
    avr->cycle += skip ? 2u : 1u;
}

static avr_t *make_core(void)
{
    avr_t *avr = avr_make_mcu_by_name("atmega328p");
    uint32_t flags = 0;
    if (!avr) {
        return 0;
    }
    avr_init(avr);
    avr->log = 0;
    avr_load_firmware(avr, &E.fw);
    scan_skips(avr);
    avr->frequency = E.freq;
    avr->sleep = no_sleep;
    boot_power_on(avr);
    E.avr = avr;
    E.cycle0 = avr->cycle;
    E.uart = 0;
    for (avr_io_t *p = avr->io_port; p; p = p->next) {
        if (p->kind && strcmp(p->kind, "uart") == 0 && ((avr_uart_t *)p)->name == '0') {
            E.uart = (avr_uart_t *)p;
        }
    }
    if (!E.uart) {
        return 0;
    }
    E.uart_irq = avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), 0);
    avr_ioctl(avr, AVR_IOCTL_UART_SET_FLAGS('0'), &flags); /* no usleep, no console echo */
    avr_irq_register_notify(E.uart_irq + UART_IRQ_OUTPUT, on_uart_out, 0);
    wrap(avr, R_UBRR0L, &E.w_ubrr0l, w_ubrr0l);
    wrap(avr, R_UCSR0A, &E.w_ucsr0a, w_ucsr0a);
    wrap(avr, R_UCSR0C, &E.w_ucsr0c, w_ucsr0c);
    wrap(avr, R_GPIOR0, &E.w_gpior0, w_gpior0);
    twi_attach(avr);
    memset(&E.io, 0, sizeof E.io);
    E.io.kind = "proleg";
    E.io.reset = on_mcu_reset;
    avr_register_io(avr, &E.io);
    return avr;
}

/* ------------------------------------------------------------------ the ABI */

/* Load an ELF for an ATmega328P at freq Hz; the host sends at host_baud. 0 or -1 (file)
 * or -2 (core). Then call emu_reset. */
EMU_API int emu_open(const char *elf_path, uint32_t freq, uint32_t host_baud)
{
    avr_global_logger_set(silent_logger);
    memset(&E.fw, 0, sizeof E.fw);
    if (elf_read_firmware(elf_path, &E.fw) != 0) {
        return -1;
    }
    strcpy(E.fw.mmcu, "atmega328p");
    E.fw.frequency = freq;
    E.freq = freq;
    E.host_baud = host_baud ? host_baud : 115200u;
    E.rxq.buf = rxq_mem;
    E.rxq.cap = RXQ_SIZE;
    E.hostq.buf = hostq_mem;
    E.hostq.cap = HOSTQ_SIZE;
    E.mark_start = E.mark_end = NO_PC;
    return make_core() ? 0 : -2;
}

/* The EEPROM keeps its bytes through a power cycle: emu_reset carries them from the old
 * core to the new one (an MCU reset keeps the core, and them, anyway). Erased (0xFF) when
 * the library is loaded. */
#define EEPROM_BYTES 1024u
static uint8_t eeprom_keep[EEPROM_BYTES];
static int eeprom_kept;

static void eeprom_move(avr_t *avr, int save)
{
    avr_eeprom_desc_t d = {eeprom_keep, 0, EEPROM_BYTES};
    if (save) {
        if (avr_ioctl(avr, AVR_IOCTL_EEPROM_GET, &d) == 0 && d.ee != eeprom_keep) {
            memcpy(eeprom_keep, d.ee, EEPROM_BYTES); /* versions that hand back a pointer */
        }
        eeprom_kept = 1;
    } else if (eeprom_kept) {
        avr_ioctl(avr, AVR_IOCTL_EEPROM_SET, &d);
    }
}

/* Power-on reset: a fresh core with the firmware, the devices powered up again with
 * `seed`, time 0, queues empty, counters cleared (markers and the PWM map are kept). */
EMU_API int emu_reset(uint32_t seed)
{
    if (E.avr) {
        eeprom_move(E.avr, 1);
        boot_power_off(E.avr);
        avr_terminate(E.avr);
        free(E.avr);
        E.avr = 0;
    }
    E.rxq.head = E.rxq.count = 0;
    E.hostq.head = E.hostq.count = 0;
    E.rx_overruns = E.rx_receiver_off = E.rxq_dropped = E.hostq_dropped = 0;
    E.gpio_mode = 0;
    E.t_head = E.t_count = 0;
    E.ticks_total = E.ticks_lost = 0;
    E.sp_min = 0xFFFFu;
    E.ov_acc = E.ov_last = 0;
    sim_mpu_power_on(seed);
    twi_unwire_all();
    if (!make_core()) {
        return -2;
    }
    eeprom_move(E.avr, 0);
    on_mcu_reset(0);
    E.mcu_resets = 0;
    return 0;
}

/* An MPU-6050 wired directly at addr (0x68..0x6F), model slot addr - 0x68. */
EMU_API void emu_imu_attach(uint8_t addr)
{
    if (addr >= SIM_MPU_BASE_ADDR && addr < SIM_MPU_BASE_ADDR + SIM_MPU_MAX) {
        twi_wire_imu((uint8_t)(addr - SIM_MPU_BASE_ADDR), addr, 0, 0);
    }
}

/* Model slot `slot` at addr, behind channel ch of the TCA9548A at mux (0: wired directly);
 * its key for the emu_imu_* calls is 0x80 | slot (or addr when wired directly). */
EMU_API void emu_imu_wire(uint8_t slot, uint8_t addr, uint8_t mux, uint8_t ch)
{
    twi_wire_imu(slot, addr, mux, ch);
}

/* Run the core for n cycles of emulated time. Returns simavr's cpu state (cpu_Done or
 * cpu_Crashed: the core has stopped; time still advances, nothing runs). */
EMU_API int emu_run_cycles(uint64_t n)
{
    avr_t *avr = E.avr;
    uint64_t target = avr->cycle + n;
    uint32_t ms = E.mark_start, me = E.mark_end;
    uint16_t sp_min = E.sp_min;
    while (avr->cycle < target) {
        uint32_t pc = avr->pc;
        uint16_t sp;
        if (pc == ms) {
            if (!E.gpio_mode) {
                busy_begin();
            }
        } else if (pc == me) {
            if (!E.gpio_mode) {
                busy_end();
            }
        }
        if (at_bad_skip(pc) && avr->state == cpu_Running) {
            uint64_t c0 = avr->cycle;
            run_skip(avr);
            if (profiling) {
                prof_cycles[(pc >> 1) & (FLASH_WORDS - 1u)] += avr->cycle - c0;
            }
        } else if (profiling) {
            uint64_t c0 = avr->cycle;
            avr->run(avr);
            prof_cycles[(pc >> 1) & (FLASH_WORDS - 1u)] += avr->cycle - c0;
        } else {
            avr->run(avr);
        }
        sp = (uint16_t)(avr->data[R_SPL] | (avr->data[R_SPH] << 8));
        if (sp < sp_min) {
            sp_min = sp;
        }
        if (avr->state == cpu_Done || avr->state == cpu_Crashed) {
            avr->cycle = target;
            break;
        }
    }
    E.sp_min = sp_min;
    return avr->state;
}

EMU_API uint64_t emu_cycles(void)
{
    return emu_now_cycles();
}

EMU_API uint32_t emu_frequency(void)
{
    return E.freq;
}

EMU_API int emu_cpu_state(void)
{
    return E.avr->state;
}

EMU_API uint32_t emu_pc(void)
{
    return E.avr->pc;
}

/* Fault injection: the core jumps to `byte_addr` (e.g. a `rjmp .` such as avr-libc's
 * __stop_program) as a wild pointer or a stuck loop would; interrupts stay as they were. */
EMU_API void emu_jump(uint32_t byte_addr)
{
    E.avr->pc = byte_addr;
}

EMU_API uint64_t emu_mcu_resets(void)
{
    return E.mcu_resets;
}

/* Data-space bytes (registers, I/O, SRAM) for tests and the reset-cause check. */
EMU_API uint32_t emu_read_data(uint16_t addr, uint8_t *out, uint32_t n)
{
    uint32_t i;
    for (i = 0; i < n && (uint32_t)addr + i <= E.avr->ramend; i++) {
        out[i] = E.avr->data[addr + i];
    }
    return i;
}

/* -- PWM ------------------------------------------------------------------------- */

EMU_API int emu_set_pwm_map(uint8_t channel, uint8_t oc)
{
    if (channel >= MAX_PWM || oc >= OC_COUNT) {
        return -1;
    }
    E.pwm_map[channel] = oc;
    if (channel >= E.n_pwm) {
        E.n_pwm = (uint8_t)(channel + 1u);
    }
    return 0;
}

EMU_API uint16_t emu_pwm_duty(uint8_t channel)
{
    return channel < E.n_pwm ? oc_duty(E.pwm_map[channel]) : 0u;
}

/* (DDRx << 8) | PORTx of port 'B', 'C' or 'D'. */
EMU_API uint16_t emu_port(char name)
{
    uint8_t base = name == 'B' ? 0x24u : name == 'C' ? 0x27u : 0x2Au;
    return (uint16_t)((E.avr->data[base] << 8) | E.avr->data[base + 1u]);
}

/* -- UART ------------------------------------------------------------------------ */

EMU_API void emu_uart_write(const uint8_t *data, uint32_t n)
{
    E.rxq_dropped += n - fifo_put(&E.rxq, data, n);
    rx_pump_start();
}

EMU_API uint32_t emu_uart_read(uint8_t *out, uint32_t cap)
{
    uint32_t n = 0;
    while (n < cap && E.hostq.count > 0u) {
        out[n++] = (uint8_t)fifo_get(&E.hostq);
    }
    return n;
}

/* Host -> board bytes lost: [0] receiver overrun, [1] receiver disabled, [2] host queue
 * full; board -> host: [3] host queue full. */
EMU_API void emu_uart_losses(uint32_t out[4])
{
    out[0] = E.rx_overruns;
    out[1] = E.rx_receiver_off;
    out[2] = E.rxq_dropped;
    out[3] = E.hostq_dropped;
}

EMU_API uint64_t emu_uart_cycles_per_byte(void)
{
    return E.uart->cycles_per_byte;
}

/* -- IMUs -------------------------------------------------------------------------- */

/* IMU keys: 0x80 | model slot, or the address of an IMU wired directly (host-sim's keys,
 * proleg.firmware.placement.sim_imu_keys). An unknown key is ignored. */
EMU_API void emu_imu_set_truth(uint8_t key, double psi_deg, double dpsi_dps)
{
    int slot = twi_imu_slot(key);
    if (slot >= 0) {
        sim_mpu_set_truth_slot((uint8_t)slot, psi_deg, dpsi_dps);
    }
}

EMU_API void emu_imu_set_fault(uint8_t key, uint8_t mode)
{
    int slot = twi_imu_slot(key);
    if (slot >= 0) {
        sim_mpu_set_fault_slot((uint8_t)slot, mode);
    }
}

EMU_API void emu_imu_set_noise(uint8_t key, double accel_ug_rthz, double gyro_dps_rthz, double accel_offset_mg)
{
    int slot = twi_imu_slot(key);
    if (slot >= 0) {
        sim_mpu_set_noise_slot((uint8_t)slot, accel_ug_rthz, gyro_dps_rthz, accel_offset_mg);
    }
}

EMU_API uint8_t emu_imu_peek_reg(uint8_t key, uint8_t reg)
{
    int slot = twi_imu_slot(key);
    return slot >= 0 ? sim_mpu_peek_slot((uint8_t)slot, reg) : 0xFFu;
}

EMU_API void emu_imu_set_startup_us(uint8_t key, uint64_t us)
{
    int slot = twi_imu_slot(key);
    if (slot >= 0) {
        twi_set_startup_us((uint8_t)slot, us);
    }
}

/* A device holds SDA low until it has seen release_clocks SCL pulses (0 = until
 * emu_i2c_hold_sda(0, ...)); power-on resets release it, MCU resets do not. */
EMU_API void emu_i2c_hold_sda(int held, uint8_t release_clocks)
{
    twi_hold_sda(held, release_clocks);
}

EMU_API uint64_t emu_i2c_transactions(void)
{
    return twi_transactions();
}

EMU_API uint64_t emu_i2c_bus_cycles(void)
{
    return twi_bus_cycles();
}

/* -- tick budget ----------------------------------------------------------------- */

EMU_API void emu_set_tick_markers(uint32_t start_pc, uint32_t end_pc)
{
    E.mark_start = start_pc;
    E.mark_end = end_pc;
}

EMU_API int emu_gpio_markers(void)
{
    return E.gpio_mode;
}

/* Completed ticks since the last call, oldest first (up to max). */
EMU_API uint32_t emu_ticks_read(uint64_t *start, uint32_t *busy, uint32_t *i2c, uint32_t max)
{
    uint32_t n = 0;
    while (n < max && E.t_count > 0u) {
        tick_rec_t *r = &E.ticks[E.t_head];
        start[n] = r->start;
        busy[n] = r->busy;
        i2c[n] = r->i2c;
        E.t_head = (E.t_head + 1u) % TICKS_SIZE;
        E.t_count--;
        n++;
    }
    return n;
}

EMU_API uint64_t emu_ticks_lost(void)
{
    return E.ticks_lost;
}

/* Cycle profile: per instruction (word) address, cycles spent executing it (interrupt
 * entry counted with the instruction it interrupted). on = 1 clears and starts it. */
EMU_API void emu_profile(int on)
{
    if (on) {
        memset(prof_cycles, 0, sizeof prof_cycles);
    }
    profiling = (uint8_t)(on != 0);
}

EMU_API uint32_t emu_profile_read(uint64_t *out, uint32_t max_words)
{
    uint32_t n = max_words < FLASH_WORDS ? max_words : FLASH_WORDS;
    memcpy(out, prof_cycles, n * sizeof *out);
    return n;
}

/* Lowest stack pointer since reset (the stack grows down from RAMEND = 0x8FF). */
EMU_API uint16_t emu_sp_min(void)
{
    return E.sp_min;
}
