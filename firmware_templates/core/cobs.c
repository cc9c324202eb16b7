/* cobs.c - COBS, see cobs.h. */
#include "cobs.h"

size_t cobs_encode_inplace(uint8_t *buf, size_t n)
{
    size_t last = 0; /* where the code byte of the current block goes */
    size_t i;
    if (n > COBS_MAX_INPLACE) {
        return 0;
    }
    for (i = 1; i <= n; i++) {
        if (buf[i] == 0) {
            buf[last] = (uint8_t)(i - last);
            last = i;
        }
    }
    buf[last] = (uint8_t)(n + 1 - last);
    return n + 1;
}

void cobs_dec_reset(cobs_dec_t *d)
{
    d->block = 0;
    d->code = 0;
}

int cobs_dec_byte(cobs_dec_t *d, uint8_t in, uint8_t *out)
{
    if (d->block > 0) { /* data byte */
        d->block--;
        *out = in;
        return 1;
    }
    /* code byte: the previous block (if any, and not a full 0xFF block) ended in a zero */
    {
        int yield_zero = d->code != 0 && d->code != 0xFF;
        d->code = in;
        d->block = (uint8_t)(in - 1);
        if (yield_zero) {
            *out = 0;
            return 1;
        }
    }
    return 0;
}

int cobs_dec_complete(const cobs_dec_t *d)
{
    return d->code != 0 && d->block == 0;
}
