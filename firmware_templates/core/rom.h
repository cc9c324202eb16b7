/* rom.h - constant tables in flash.
 *
 * Tables that never change (thresholds, gait steps, the transition bitmap) are declared
 * `static const T name[] ROM = {...}` and read through ROM_U8/ROM_U16/ROM_I16 (a whole row: ROM_COPY). On AVR
 * they stay in program memory (PROGMEM + pgm_read_*); everywhere else they are plain
 * const data in .rodata and the readers are ordinary loads.
 */
#ifndef PROLEG_ROM_H
#define PROLEG_ROM_H

#include <stdint.h>

#if defined(__AVR__)
#include <avr/pgmspace.h>
#define ROM PROGMEM
#define ROM_COPY(dst, src, n) memcpy_P((dst), (src), (n))
#define ROM_U8(p) ((uint8_t)pgm_read_byte(p))
#define ROM_U16(p) ((uint16_t)pgm_read_word(p))
#define ROM_I16(p) ((int16_t)pgm_read_word(p))
#define ROM_U32(p) ((uint32_t)pgm_read_dword(p))
#else
#include <string.h>
#define ROM
#define ROM_COPY(dst, src, n) memcpy((dst), (src), (n))
#define ROM_U8(p) (*(const uint8_t *)(p))
#define ROM_U16(p) (*(const uint16_t *)(p))
#define ROM_I16(p) (*(const int16_t *)(p))
#define ROM_U32(p) (*(const uint32_t *)(p))
#endif

#endif /* PROLEG_ROM_H */
