/* skips.c - the skip instructions simavr 1.6 gets wrong, found in the flash and run here.
 *
 * Contract. skips_scan(avr) marks, once the firmware is in flash, every skip whose next
 * instruction simavr would take for two words when it is one; skips_at(pc) (harness.h) says
 * whether the core stands on such a skip, and skips_run(avr) executes it instead of
 * simavr: pc and cycle count as on the chip. The run loop asks before every instruction.
 *
 * simavr 1.6 decides whether the instruction after a skip (CPSE, SBRC, SBRS, SBIC, SBIS)
 * is one or two words with the mask 0xFC0F, so it also takes ADIW/SBIW with some operands
 * (0x9[46]xF and 0x9[46]xE, e.g. adiw r24,0x1f = 0x964F), and a few other opcodes, for
 * LDS/STS/JMP/CALL and skips two words instead of one: the instruction after the one-word
 * one is skipped too (avr-gcc emits `cpse r15,r1; adiw r24,0x1f` for `if (x) i += 31;`; it
 * made the Nano start every gait of a 3-limb robot with 0 steps). The run loop executes
 * those skips itself (AVR instruction set manual: 1 cycle if the condition is false, 2 if
 * it skips a one-word instruction).
 */
#include <string.h>

#include "harness.h"

uint8_t skips_bad[FLASH_WORDS / 8u]; /* word addresses of skips simavr 1.6 gets wrong */

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

void skips_scan(const avr_t *avr)
{
    uint32_t w, words = avr->flashend + 1u < 2u * FLASH_WORDS ? (avr->flashend + 1u) / 2u : FLASH_WORDS;
    memset(skips_bad, 0, sizeof skips_bad);
    for (w = 0; w + 1u < words; w++) {
        uint16_t next = flash_word(avr, w + 1u);
        if (is_skip(flash_word(avr, w)) && simavr_says_two_words(next) && !is_two_words(next)) {
            skips_bad[w >> 3] = (uint8_t)(skips_bad[w >> 3] | (1u << (w & 7u)));
        }
    }
}

/* Execute the skip at pc whose next instruction is one word (only where skips_at). */
void skips_run(avr_t *avr)
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
