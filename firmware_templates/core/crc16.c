/* crc16.c - CRC-16/CCITT-FALSE, see crc16.h. */
#include "crc16.h"

uint16_t crc16_ccitt_update(uint16_t crc, uint8_t byte)
{
    uint8_t x = (uint8_t)((crc >> 8) ^ byte);
    x ^= (uint8_t)(x >> 4);
    return (uint16_t)((uint16_t)(crc << 8) ^ (uint16_t)((uint16_t)x << 12) ^ (uint16_t)((uint16_t)x << 5) ^ x);
}

uint16_t crc16_ccitt(uint16_t crc, const uint8_t *data, size_t n)
{
    while (n--) {
        crc = crc16_ccitt_update(crc, *data++);
    }
    return crc;
}
