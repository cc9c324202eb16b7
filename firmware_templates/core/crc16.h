/* crc16.h - CRC-16/CCITT-FALSE: poly 0x1021, init 0xFFFF, no reflection, no final xor.
 *
 * Check value: crc16_ccitt(CRC16_INIT, "123456789", 9) == 0x29B1. Table-free (a few
 * shifts per byte) so it costs no flash for a table on small MCUs. Python equivalent:
 * binascii.crc_hqx(data, 0xFFFF).
 */
#ifndef PROLEG_CRC16_H
#define PROLEG_CRC16_H

#include <stddef.h>
#include <stdint.h>

#define CRC16_INIT 0xFFFFu

/* CRC after one more byte. */
uint16_t crc16_ccitt_update(uint16_t crc, uint8_t byte);
/* CRC after n more bytes (pass CRC16_INIT to start). */
uint16_t crc16_ccitt(uint16_t crc, const uint8_t *data, size_t n);

#endif /* PROLEG_CRC16_H */
