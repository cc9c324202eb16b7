/* proto.c - the link protocol runtime: interprets the descriptor tables of proto_gen.c.
 * Contract in proto.h. No malloc, no recursion; the only buffers are the caller's. */
#include "proto.h"

#include <string.h>

#include "cobs.h"
#include "crc16.h"

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

/* Descriptor of message id, or NULL. */
static const proto_msgdesc_t *find_desc(uint8_t id)
{
    uint8_t i;
    for (i = 0; i < PROTO_N_MESSAGES; i++) {
        if (PROTO_READ_BYTE(&proto_messages[i].id) == id) {
            return &proto_messages[i];
        }
    }
    return NULL;
}

/* little-endian wire <-> native value, through memcpy so alignment never matters */
static void get_le(const uint8_t *src, uint8_t size, uint8_t *dst)
{
    if (size == 1) {
        *dst = *src;
    } else if (size == 2) {
        uint16_t v = (uint16_t)(src[0] | ((uint16_t)src[1] << 8));
        memcpy(dst, &v, 2);
    } else {
        uint32_t v = (uint32_t)src[0] | ((uint32_t)src[1] << 8) | ((uint32_t)src[2] << 16) |
                     ((uint32_t)src[3] << 24);
        memcpy(dst, &v, 4);
    }
}

static void put_le(const uint8_t *src, uint8_t size, uint8_t *dst)
{
    if (size == 1) {
        *dst = *src;
    } else if (size == 2) {
        uint16_t v;
        memcpy(&v, src, 2);
        dst[0] = (uint8_t)v;
        dst[1] = (uint8_t)(v >> 8);
    } else {
        uint32_t v;
        memcpy(&v, src, 4);
        dst[0] = (uint8_t)v;
        dst[1] = (uint8_t)(v >> 8);
        dst[2] = (uint8_t)(v >> 16);
        dst[3] = (uint8_t)(v >> 24);
    }
}

uint8_t proto_unpack(const uint8_t *frame, size_t n, proto_msg_t *msg)
{
    const proto_msgdesc_t *d;
    const proto_field_t *f;
    uint8_t *base = (uint8_t *)&msg->u;
    size_t pos = 1;
    uint8_t i, nf;

    if (n < 1 || (d = find_desc(frame[0])) == NULL) {
        return PROTO_ERR_UNKNOWN_MESSAGE;
    }
    msg->id = frame[0];
    memset(&msg->u, 0, sizeof msg->u);
    f = &proto_fields[PROTO_READ_BYTE(&d->first)];
    nf = PROTO_READ_BYTE(&d->n);
    for (i = 0; i < nf; i++, f++) {
        uint8_t type = PROTO_READ_BYTE(&f->type);
        uint8_t max = PROTO_READ_BYTE(&f->max);
        uint8_t *dst = base + PROTO_READ_BYTE(&f->offset);
        uint8_t size = type_size(type);
        uint8_t count = 1, k;
        if ((type & 0x0Fu) == PROTO_T_CHAR) {
            size = 1;
            count = max;
        } else if (type & PROTO_F_ARRAY) {
            if (pos >= n) {
                return PROTO_ERR_BAD_LENGTH;
            }
            count = frame[pos++];
            if (count > max) {
                return PROTO_ERR_TOO_LONG;
            }
            base[PROTO_READ_BYTE(&f->count_offset)] = count;
        }
        if (n - pos < (size_t)count * size) {
            return PROTO_ERR_BAD_LENGTH;
        }
        for (k = 0; k < count; k++) {
            get_le(frame + pos, size, dst);
            pos += size;
            dst += size;
        }
    }
    return pos == n ? 0 : PROTO_ERR_BAD_LENGTH;
}

size_t proto_pack(const proto_msg_t *msg, uint8_t *out, size_t cap)
{
    const proto_msgdesc_t *d = find_desc(msg->id);
    const proto_field_t *f;
    const uint8_t *base = (const uint8_t *)&msg->u;
    size_t pos = 0;
    uint8_t i, nf;

    if (d == NULL || cap < 1) {
        return 0;
    }
    out[pos++] = msg->id;
    f = &proto_fields[PROTO_READ_BYTE(&d->first)];
    nf = PROTO_READ_BYTE(&d->n);
    for (i = 0; i < nf; i++, f++) {
        uint8_t type = PROTO_READ_BYTE(&f->type);
        uint8_t max = PROTO_READ_BYTE(&f->max);
        const uint8_t *src = base + PROTO_READ_BYTE(&f->offset);
        uint8_t size = type_size(type);
        uint8_t count = 1, k;
        if ((type & 0x0Fu) == PROTO_T_CHAR) {
            size = 1;
            count = max;
        } else if (type & PROTO_F_ARRAY) {
            count = base[PROTO_READ_BYTE(&f->count_offset)];
            if (count > max || pos >= cap) {
                return 0;
            }
            out[pos++] = count;
        }
        if (cap - pos < (size_t)count * size) {
            return 0;
        }
        for (k = 0; k < count; k++) {
            put_le(src, size, out + pos);
            pos += size;
            src += size;
        }
    }
    return pos;
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
    uint8_t err;
    uint16_t crc;
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
    /* delimiter: judge the frame, then start the next one */
    if (rx->cobs.code == 0) { /* empty frame: 00 00 */
        return 0;
    }
    if (rx->overflow || !cobs_dec_complete(&rx->cobs) || rx->len < 3) {
        rx->count.framing_errors++;
        rx_restart(rx);
        return 0;
    }
    crc = crc16_ccitt(CRC16_INIT, rx->buf, (size_t)rx->len - 2);
    if ((uint8_t)crc != rx->buf[rx->len - 2] || (uint8_t)(crc >> 8) != rx->buf[rx->len - 1]) {
        rx->count.crc_errors++;
        rx_restart(rx);
        return 0;
    }
    err = proto_unpack(rx->buf, (size_t)rx->len - 2, msg);
    if (err == 0) {
        rx->count.frames_ok++;
    } else {
        if (err == PROTO_ERR_UNKNOWN_MESSAGE) {
            rx->count.unknown_ids++;
        } else if (err == PROTO_ERR_TOO_LONG) {
            rx->count.bad_value++;
        } else {
            rx->count.bad_length++;
        }
        rx->rej_error = err;
        rx->rej_id = rx->buf[0];
        rx->rej_token = rx->len > 3 ? rx->buf[1] : 0;
    }
    rx_restart(rx);
    return err == 0;
}
