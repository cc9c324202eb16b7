/* boot.c - the avr-emu board's flash memory and boot section: what a bootloader needs.
 *
 * A Nano's ATmega328P is fused with BOOTRST programmed and BOOTSZ = 256 words (datasheet
 * §27.8, Table 27-7 and §28.2 fuse defaults of the Arduino boards: high fuse 0xDE), so every
 * reset starts at the boot section, 0x7E00, where optiboot lives. emu_set_boot_reset gives
 * the core that reset vector (simavr's avr->reset_pc, used by avr_reset, hence also by its
 * watchdog reset). Flash is non-volatile: once a boot reset vector is set, a power-on reset
 * (emu_reset) keeps whatever the bootloader wrote instead of reloading the ELF.
 * simavr 1.6 itself performs the SPM page erase / page write (avr_flash.c).
 *
 * emu_external_reset is the RESET pin pulled low: the Nano's auto-reset (DTR through a
 * 100 nF capacitor) when a host opens the serial port. The MCU Status Register then holds
 * EXTRF only (datasheet §10.9.1), which is what optiboot looks at to stay in the loader.
 *
 * Watchdog prescaler. simavr 1.6 keeps the old timeout when the prescaler changes while
 * the watchdog runs (avr_watchdog_write reads the "old" WDP bits after storing the new
 * ones, so it never re-arms its timer). Optiboot leaves through exactly that path: after
 * LEAVE_PROGMODE, or on a byte it does not expect, it shortens the running 1 s watchdog to
 * 16 ms and spins; plain simavr starts the application ~1 s late instead of ~16 ms. A
 * change of WDP while the watchdog is enabled re-arms it with the new period (as the
 * `wdr` that avr-libc's wdt_enable and optiboot issue just before makes it on the chip).
 *
 * Without emu_set_boot_reset nothing else here changes the board: the ELF is loaded at 0
 * and starts there (the existing avr-emu behaviour).
 */
#include <string.h>

#include "avr_watchdog.h"
#include "harness.h"
#include "sim_io.h"

#define EMU_API __attribute__((visibility("default")))

#define R_MCUSR_ 0x54u
#define EXTRF_BIT 0x02u
#define FLASH_BYTES 32768u

#define R_WDTCSR 0x60u
#define WDT_WDE 0x08u
#define WDT_WDIE 0x40u
#define WDT_WDP 0x27u /* WDP3 (bit 5), WDP2..0 */

static avr_io_write_t wdt_write_c; /* simavr's WDTCSR write handler */
static void *wdt_write_param;
static uint32_t boot_pc;              /* byte address of the reset vector; 0 = application */
static uint8_t flash_kept[FLASH_BYTES]; /* flash across a power-on reset (boot mode only) */

void boot_power_off(avr_t *avr)
{
    if (boot_pc && avr) {
        memcpy(flash_kept, avr->flash, FLASH_BYTES);
    }
}

static void wdtcsr_write(struct avr_t *avr, avr_io_addr_t addr, uint8_t v, void *param)
{
    uint8_t before = avr->data[addr];
    (void)param;
    wdt_write_c(avr, addr, v, wdt_write_param);
    if (((before ^ avr->data[addr]) & WDT_WDP) && (avr->data[addr] & (WDT_WDE | WDT_WDIE))) {
        avr_ioctl(avr, AVR_IOCTL_WATCHDOG_RESET, 0); /* re-arm with the new period */
    }
}

void boot_power_on(avr_t *avr)
{
    avr_io_addr_t a = AVR_DATA_TO_IO(R_WDTCSR);
    if (avr->io[a].w.c && avr->io[a].w.c != wdtcsr_write) {
        wdt_write_c = avr->io[a].w.c;
        wdt_write_param = avr->io[a].w.param;
        avr->io[a].w.c = wdtcsr_write;
        avr->io[a].w.param = 0;
    }
    if (boot_pc) {
        memcpy(avr->flash, flash_kept, FLASH_BYTES);
        avr->reset_pc = boot_pc;
        avr->pc = boot_pc;
    }
}

/* BOOTRST: every reset starts at byte address `byte_addr` (0 = back to the application
 * vector). Takes effect now (the core restarts there, as a power-on would). */
EMU_API void emu_set_boot_reset(uint32_t byte_addr)
{
    avr_t *avr = emu_core();
    boot_pc = byte_addr;
    avr->reset_pc = byte_addr;
    avr->pc = byte_addr;
}

/* The RESET pin: an external reset (MCUSR = EXTRF). */
EMU_API void emu_external_reset(void)
{
    avr_t *avr = emu_core();
    avr_reset(avr);
    avr->data[R_MCUSR_] = EXTRF_BIT;
}

/* Program memory, as a programmer would write/read it. 0 or -1 (out of range). */
EMU_API int emu_flash_write(uint32_t addr, const uint8_t *data, uint32_t n)
{
    avr_t *avr = emu_core();
    if ((uint64_t)addr + n > (uint64_t)avr->flashend + 1u) {
        return -1;
    }
    memcpy(avr->flash + addr, data, n);
    return 0;
}

EMU_API int emu_flash_read(uint32_t addr, uint8_t *out, uint32_t n)
{
    avr_t *avr = emu_core();
    if ((uint64_t)addr + n > (uint64_t)avr->flashend + 1u) {
        return -1;
    }
    memcpy(out, avr->flash + addr, n);
    return 0;
}
