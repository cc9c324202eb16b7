/* cycles.c - the arm-emu board's cycle counter: a native unicorn block hook.
 *
 * Contract. emu_block_hook() is registered as a UC_HOOK_BLOCK callback. For every
 * translated block it adds that block's estimated Cortex-M3 cycles (a prefix-sum table
 * over the firmware's flash, one entry per halfword, computed in Python) to emu_cycles,
 * and stops the emulation (uc_emu_stop, passed in as a pointer) once emu_cycles
 * reaches emu_deadline. A block that is a single `b .` (self-loop) jumps emu_cycles to
 * the deadline at once: a hung core costs no host time. No allocation, no state
 * beyond the globals below; one emulated board per loaded copy of this library.
 */
#include <stdint.h>

typedef int (*emu_stop_fn)(void *uc);

uint64_t emu_cycles;
uint64_t emu_deadline;
uint64_t emu_blocks;

static const uint32_t *cum;   /* cum[i] = cycles of the instructions before halfword i */
static uint32_t cum_base;     /* address of halfword 0 */
static uint32_t cum_n;        /* entries in cum (halfwords + 1) */
static const uint16_t *code;  /* the flash image, to recognise `b .` */
static emu_stop_fn stop_fn;

void emu_setup(const uint32_t *table, uint32_t base, uint32_t n, const uint16_t *image, void *stop)
{
    cum = table;
    cum_base = base;
    cum_n = n;
    code = image;
    stop_fn = (emu_stop_fn)stop;
    emu_cycles = 0;
    emu_deadline = 0;
    emu_blocks = 0;
}

void emu_block_hook(void *uc, uint64_t address, uint32_t size, void *user)
{
    uint32_t a = (uint32_t)address;
    (void)user;
    emu_blocks++;
    if (a >= cum_base && a + size <= cum_base + 2u * (cum_n - 1u)) {
        uint32_t i = (a - cum_base) >> 1;
        uint32_t j = (a + size - cum_base) >> 1;
        emu_cycles += (uint64_t)(cum[j] - cum[i]) + 2u; /* +2: pipeline refill of the branch into it */
        if (size == 2u && code[i] == 0xE7FEu && emu_cycles < emu_deadline) {
            emu_cycles = emu_deadline;
        }
    } else {
        emu_cycles += size / 2u + 2u;
    }
    if (emu_cycles >= emu_deadline && stop_fn) {
        stop_fn(uc);
    }
}
