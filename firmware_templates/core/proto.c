/* proto.c - the link protocol runtime: interprets the descriptor tables of proto_gen.c.
 * Contract in proto.h. No malloc, no recursion; the only buffers are the caller's. */
#include "proto.h"

#include <string.h>

#include "cobs.h"
#include "crc16.h"

#if PROTO_PACKED_LAYOUT
typedef proto_msglayout_t desc_t;
#else
typedef proto_msgdesc_t desc_t;

static uint8_t type_size(uint8_t t)
{
    switch (t & 0x0Fu) {
    case PROTO_T_U16:
    case PROTO_T_I16:
        return 2;
    case PROTO_T_U32:
    case PROTO_T_I32:
        return 4;
    default:
        return 1;
    }
}

#endif

/* Descriptor of message id, or NULL. */
static const desc_t *find_desc(uint8_t id)
{
    uint8_t i;
    for (i = 0; i < PROTO_N_MESSAGES; i++) {
        if (PROTO_READ_BYTE(&proto_messages[i].id) == id) {
            return &proto_messages[i];
        }
    }
    return NULL;
}

#if !PROTO_PACKED_LAYOUT
/* Copy count elements of size bytes between the little-endian wire and native memory.
 * The same operation in both directions; the endianness test folds to a constant. */
static void copy_elems(uint8_t *dst, const uint8_t *src, uint8_t count, uint8_t size)
{
    const uint16_t one = 1;
    uint8_t little;
    memcpy(&little, &one, 1);
    if (little || size == 1) {
        memcpy(dst, src, (size_t)count * size);
    } else {
        uint8_t k, j;
        for (k = 0; k < count; k++, dst += size, src += size) {
            for (j = 0; j < size; j++) {
                dst[j] = src[size - 1u - j];
            }
        }
    }
}

/* Walk the fields of message d, copying from src to dst. Packing: src = struct, dst = wire;
 * unpacking: src = wire, dst = struct. wire[0] is the id, fields start at wire[1], the wire
 * holds at most limit bytes. Returns 0 and sets *end to the wire length after the last
 * field, or PROTO_ERR_BAD_LENGTH (out of wire bytes) / PROTO_ERR_TOO_LONG (count > max). */
static uint8_t walk(const desc_t *d, const uint8_t *src, uint8_t *dst, uint8_t limit, uint8_t packing,
                    uint8_t *end)
{
    const proto_field_t *f = &proto_fields[PROTO_READ_BYTE(&d->first)];
    uint8_t nf = PROTO_READ_BYTE(&d->n);
    uint8_t pos = 1, i;
    for (i = 0; i < nf; i++, f++) {
        uint8_t type = PROTO_READ_BYTE(&f->type);
        uint8_t max = PROTO_READ_BYTE(&f->max);
        uint8_t off = PROTO_READ_BYTE(&f->offset);
        uint8_t size = type_size(type), count = 1;
        uint16_t nbytes;
        if ((type & 0x0Fu) == PROTO_T_CHAR) {
            count = max;
        } else if (type & PROTO_F_ARRAY) {
            uint8_t coff = PROTO_READ_BYTE(&f->count_offset);
            if (pos >= limit) {
                return PROTO_ERR_BAD_LENGTH;
            }
            count = packing ? src[coff] : src[pos];
            dst[packing ? pos : coff] = count;
            pos++;
            if (count > max) {
                return PROTO_ERR_TOO_LONG;
            }
        }
        nbytes = (uint16_t)((uint16_t)count * size);
        if ((uint16_t)(limit - pos) < nbytes) {
            return PROTO_ERR_BAD_LENGTH;
        }
        if (packing) {
            copy_elems(dst + pos, src + off, count, size);
        } else {
            copy_elems(dst + off, src + pos, count, size);
        }
        pos = (uint8_t)(pos + nbytes);
    }
    *end = pos;
    return 0;
}
#else
/* The same walk over the message's layout string: mem runs through the struct, pos through
 * the wire; a struct is its wire bytes with each array at its capacity. Not inlined: packing
 * (tx) and unpacking (rx) share one copy. */
#if defined(__GNUC__)
__attribute__((noinline))
#endif
static uint8_t walk(const desc_t *d, const uint8_t *src, uint8_t *dst, uint8_t limit, uint8_t packing,
                    uint8_t *end)
{
    const uint8_t *l = &proto_layouts[PROTO_READ_BYTE(&d->first)];
    uint8_t *mem = (uint8_t *)(packing ? src : dst);
    uint8_t *wire = packing ? dst : (uint8_t *)src;
    uint8_t pos = 1, b;
    while ((b = PROTO_READ_BYTE(l++)) != 0u) {
        uint8_t n = b, cap = b; /* wire bytes, struct bytes */
        if (b & PROTO_L_ARRAY) {
            uint8_t size = (uint8_t)(b & 0x7Fu), max = PROTO_READ_BYTE(l++), count;
            if (pos >= limit) {
                return PROTO_ERR_BAD_LENGTH;
            }
            if (packing) {
                wire[pos] = *mem;
            } else {
                *mem = wire[pos];
            }
            count = *mem++;
            pos++;
            if (count > max) {
                return PROTO_ERR_TOO_LONG;
            }
            n = (uint8_t)(count * size); /* ≤ 24 × 4: capacities and sizes are the definition's */
            cap = (uint8_t)(max * size);
        }
        if ((uint8_t)(limit - pos) < n) {
            return PROTO_ERR_BAD_LENGTH;
        }
        if (packing) {
            memcpy(wire + pos, mem, n);
        } else {
            memcpy(mem, wire + pos, n);
        }
        pos = (uint8_t)(pos + n);
        mem += cap;
    }
    *end = pos;
    return 0;
}
#endif

uint8_t proto_unpack(const uint8_t *frame, size_t n, proto_msg_t *msg)
{
    const desc_t *d;
    uint8_t end, err;
    if (n < 1 || (d = find_desc(frame[0])) == NULL) {
        return PROTO_ERR_UNKNOWN_MESSAGE;
    }
    if (n > PROTO_MAX_FRAME) {
        return PROTO_ERR_BAD_LENGTH;
    }
    msg->id = frame[0];
    memset(&msg->u, 0, sizeof msg->u);
    err = walk(d, frame, (uint8_t *)&msg->u, (uint8_t)n, 0, &end);
    if (err == 0 && end != n) {
        err = PROTO_ERR_BAD_LENGTH;
    }
    return err;
}

size_t proto_pack(const proto_msg_t *msg, uint8_t *out, size_t cap)
{
    const desc_t *d = find_desc(msg->id);
    uint8_t end;
    if (d == NULL || cap < 1) {
        return 0;
    }
    out[0] = msg->id;
    if (walk(d, (const uint8_t *)&msg->u, out, (uint8_t)(cap > 255 ? 255 : cap), 1, &end) != 0) {
        return 0;
    }
    return end;
}

size_t proto_encode(const proto_msg_t *msg, uint8_t *out, size_t cap)
{
    size_t n, len;
    uint16_t crc;
    if (cap < 4) {
        return 0;
    }
    /* out[0] = COBS code, out[1..n] = id + payload, then crc (2), then delimiter (1) */
    n = proto_pack(msg, out + 1, cap - 4);
    if (n == 0 || n + 2 > PROTO_MAX_FRAME) {
        return 0;
    }
    crc = crc16_ccitt(CRC16_INIT, out + 1, n);
    out[n + 1] = (uint8_t)crc;
    out[n + 2] = (uint8_t)(crc >> 8);
    len = cobs_encode_inplace(out, n + 2);
    out[len] = 0;
    return len + 1;
}

static void rx_restart(proto_rx_t *rx)
{
    rx->len = 0;
    rx->overflow = 0;
    cobs_dec_reset(&rx->cobs);
}

void proto_rx_init(proto_rx_t *rx)
{
    memset(rx, 0, sizeof *rx);
    rx_restart(rx);
}

int proto_rx_byte(proto_rx_t *rx, uint8_t byte, proto_msg_t *msg)
{
    uint32_t *counter;
    uint8_t err = 0;
    rx->rej_error = 0;
    if (byte != 0) {
        uint8_t out;
        if (cobs_dec_byte(&rx->cobs, byte, &out)) {
            if (rx->len < PROTO_MAX_FRAME) {
                rx->buf[rx->len++] = out;
            } else {
                rx->overflow = 1;
            }
        }
        return 0;
    }
    /* delimiter: judge the frame (exactly one counter), then start the next one */
    if (rx->cobs.code == 0) { /* empty frame: 00 00 */
        return 0;
    }
    if (rx->overflow || !cobs_dec_complete(&rx->cobs) || rx->len < 3) {
        counter = &rx->count.framing_errors;
    } else {
        uint8_t n = (uint8_t)(rx->len - 2);
        uint16_t crc = crc16_ccitt(CRC16_INIT, rx->buf, n);
        if (crc != (uint16_t)(rx->buf[n] | (uint16_t)rx->buf[n + 1] << 8)) { /* little-endian */
            counter = &rx->count.crc_errors;
        } else {
            err = proto_unpack(rx->buf, n, msg);
            if (err == 0) {
                counter = &rx->count.frames_ok;
            } else {
                counter = err == PROTO_ERR_UNKNOWN_MESSAGE ? &rx->count.unknown_ids
                          : err == PROTO_ERR_TOO_LONG      ? &rx->count.bad_value
                                                           : &rx->count.bad_length;
                rx->rej_error = err;
                rx->rej_id = rx->buf[0];
                rx->rej_token = n > 1 ? rx->buf[1] : 0;
            }
        }
    }
    (*counter)++;
    rx_restart(rx);
    return counter == &rx->count.frames_ok;
}
