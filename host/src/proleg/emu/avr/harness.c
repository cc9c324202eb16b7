/* harness.c - the avr-emu board's simavr core, run loop, resets and tick markers.
 * See harness.h; the Python side is proleg/emu/avr/board.py (ctypes), the ABI is the
 * list of EMU_API functions here and in uart.c (the UART link), pwm.c (the PWM read-out),
 * i2cbus.c (the IMUs on the I2C bus) and boot.c (flash and the boot section).
 *
 * Run loop. emu_run_cycles steps the core an instruction at a time: it watches the tick
 * markers' program addresses, runs the skips of skips.c itself, and keeps the cycle
 * profile and the lowest stack pointer.
 *
 * Tick markers. A control tick's busy time runs from the moment the firmware leaves its
 * tick wait to the moment it enters it again. Firmware that writes GPIOR0 (bit 0 = 1 at
 * the start of the tick's work, 0 at its end) is measured from those writes; otherwise
 * Python gives two program addresses found in the ELF (the first instruction after the
 * wait and the first instruction of the wait): reaching one starts, the other ends the
 * busy time. Each completed tick is recorded: start, busy cycles, and the cycles the I2C
 * bus was owned (START..STOP) during the busy time. The lowest stack pointer seen is kept.
 */
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "avr_eeprom.h"
#include "harness.h"
#include "sim_cycle_timers.h"
#include "sim_elf.h"
#include "sim_interrupts.h"
#include "sim_io.h"
#include "sim_irq.h"
#include "sim_mpu6050.h"

#define EMU_API __attribute__((visibility("default")))

#define R_GPIOR0 0x3Eu

#define TICKS_SIZE 16384u
#define NO_PC 0xFFFFFFFFu

typedef struct {
    uint64_t start;
    uint32_t busy, i2c;
} tick_rec_t;

static uint64_t prof_cycles[FLASH_WORDS]; /* cycles spent per instruction address */
static uint8_t profiling;

static struct {
    avr_t *avr;
    elf_firmware_t fw;
    uint32_t freq;
    uint64_t cycle0; /* avr->cycle at the last power-on */
    avr_io_t io;     /* our module: its reset hook runs on every MCU reset */
    emu_wrapped_t w_gpior0;
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

uint64_t emu_power_on_cycle(void)
{
    return E.cycle0;
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

/* ------------------------------------------------------------------ register hooks */

void emu_call_wrapped(const emu_wrapped_t *w, avr_t *avr, avr_io_addr_t addr, uint8_t v)
{
    if (w->c) {
        w->c(avr, addr, v, w->param);
    } else {
        avr->data[addr] = v;
    }
}

void emu_wrap_write(avr_t *avr, uint16_t reg, emu_wrapped_t *save, avr_io_write_t w)
{
    avr_io_addr_t a = AVR_DATA_TO_IO(reg);
    save->c = avr->io[a].w.c;
    save->param = avr->io[a].w.param;
    avr->io[a].w.c = w;
    avr->io[a].w.param = 0;
}

/* GPIOR0 bit 0: the firmware's own tick markers (see the top). */
static void w_gpior0(struct avr_t *avr, avr_io_addr_t addr, uint8_t v, void *param)
{
    uint8_t was = avr->data[addr];
    (void)param;
    emu_call_wrapped(&E.w_gpior0, avr, addr, v);
    E.gpio_mode = 1;
    if ((v & 1u) && !(was & 1u)) {
        busy_begin();
    } else if (!(v & 1u) && (was & 1u)) {
        busy_end();
    }
}

/* ------------------------------------------------------------------ reset */

/* Every MCU reset (power-on, watchdog, ...): the peripherals we own start again. */
static void on_mcu_reset(struct avr_io_t *io)
{
    (void)io;
    twi_reset();
    E.busy = 0;
    E.i2c_owned = 0;
    E.mcu_resets++;
    uart_mcu_reset();
}

static avr_t *make_core(void)
{
    avr_t *avr = avr_make_mcu_by_name("atmega328p");
    if (!avr) {
        return 0;
    }
    avr_init(avr);
    avr->log = 0;
    avr_load_firmware(avr, &E.fw);
    skips_scan(avr);
    avr->frequency = E.freq;
    avr->sleep = no_sleep;
    boot_power_on(avr);
    E.avr = avr;
    E.cycle0 = avr->cycle;
    if (uart_attach(avr) != 0) {
        return 0;
    }
    emu_wrap_write(avr, R_GPIOR0, &E.w_gpior0, w_gpior0);
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
    uart_open(freq, host_baud ? host_baud : 115200u);
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
    uart_power_on();
    E.gpio_mode = 0;
    E.t_head = E.t_count = 0;
    E.ticks_total = E.ticks_lost = 0;
    E.sp_min = 0xFFFFu;
    E.ov_acc = E.ov_last = 0;
    sim_mpu_power_on(seed);
    i2cbus_unwire_all();
    if (!make_core()) {
        return -2;
    }
    eeprom_move(E.avr, 0);
    on_mcu_reset(0);
    E.mcu_resets = 0;
    return 0;
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
        if (skips_at(pc) && avr->state == cpu_Running) {
            uint64_t c0 = avr->cycle;
            skips_run(avr);
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

/* -- I2C ------------------------------------------------------------------------- */

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
