/* cobs.h - Consistent Overhead Byte Stuffing for short frames (< 254 bytes).
 *
 * Encoding is done in place: the caller puts n data bytes at buf[1..n] (buf[0] is scratch)
 * and gets the n + 1 encoded bytes (no zero among them) at buf[0..n]. The 0x00 delimiter is
 * the caller's business. Same output as Python's cobs.cobs.encode for n <= 253.
 *
 * Decoding is incremental, one non-zero wire byte at a time, so a receiver needs no second
 * buffer: cobs_dec_byte yields at most one decoded byte per input byte; at the delimiter,
 * cobs_dec_complete says whether the frame was well-formed (its last block complete).
 */
#ifndef PROLEG_COBS_H
#define PROLEG_COBS_H

#include <stddef.h>
#include <stdint.h>

#define COBS_MAX_INPLACE 253u

/* Encode buf[1..n] in place into buf[0..n]; returns n + 1, or 0 if n > COBS_MAX_INPLACE. */
size_t cobs_encode_inplace(uint8_t *buf, size_t n);

typedef struct {
    uint8_t block; /* data bytes left in the current block; 0 = next byte is a code */
    uint8_t code;  /* code of the current block; 0 = no byte seen since reset */
} cobs_dec_t;

void cobs_dec_reset(cobs_dec_t *d);
/* Feed one non-zero encoded byte; returns 1 and sets *out when it yields a decoded byte. */
int cobs_dec_byte(cobs_dec_t *d, uint8_t in, uint8_t *out);
/* 1 if the bytes fed since reset form a complete encoding (at least one byte, last block full). */
int cobs_dec_complete(const cobs_dec_t *d);

#endif /* PROLEG_COBS_H */
