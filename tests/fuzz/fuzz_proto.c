/* fuzz_proto.c - libFuzzer harness of the link decoder (core/proto.c, core/cobs.c).
 *
 * The input is a byte stream from the host. Every frame the decoder accepts must encode
 * again (proto_encode) into bytes that decode to a message that encodes to the same bytes
 * (round trip), the error counters only ever grow, and the raw input survives a COBS
 * encode/decode round trip. ASan/UBSan catch any out-of-bounds access.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "cobs.h"
#include "proto.h"

static void reencode_roundtrip(const proto_msg_t *m)
{
    static uint8_t a[PROTO_MAX_ENCODED], b[PROTO_MAX_ENCODED];
    proto_rx_t rx2;
    proto_msg_t m2;
    size_t na, nb, i;
    int got = 0;
    na = proto_encode(m, a, sizeof a);
    if (na == 0u) {
        abort(); /* a decoded message must be encodable */
    }
    proto_rx_init(&rx2);
    for (i = 0; i < na; i++) {
        if (proto_rx_byte(&rx2, a[i], &m2)) {
            got++;
        }
    }
    if (got != 1) {
        abort();
    }
    nb = proto_encode(&m2, b, sizeof b);
    if (nb != na || memcmp(a, b, na) != 0) {
        abort();
    }
}

static void cobs_roundtrip(const uint8_t *data, size_t size)
{
    uint8_t buf[COBS_MAX_INPLACE + 1u], out[COBS_MAX_INPLACE];
    cobs_dec_t d;
    size_t n = size > COBS_MAX_INPLACE ? COBS_MAX_INPLACE : size, enc, i, k = 0;
    memcpy(buf + 1, data, n);
    enc = cobs_encode_inplace(buf, n);
    if (enc != n + 1u) {
        abort();
    }
    cobs_dec_reset(&d);
    for (i = 0; i < enc; i++) {
        uint8_t o;
        if (buf[i] == 0u) {
            abort(); /* no zero inside an encoding */
        }
        if (cobs_dec_byte(&d, buf[i], &o)) {
            if (k >= sizeof out) {
                abort();
            }
            out[k++] = o;
        }
    }
    if (!cobs_dec_complete(&d) || k != n || memcmp(out, data, n) != 0) {
        abort();
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static proto_rx_t rx;
    proto_msg_t m;
    proto_counters_t before;
    size_t i;
    proto_rx_init(&rx);
    for (i = 0; i < size; i++) {
        before = rx.count;
        if (proto_rx_byte(&rx, data[i], &m)) {
            reencode_roundtrip(&m);
        }
        if (rx.count.frames_ok < before.frames_ok || rx.count.crc_errors < before.crc_errors ||
            rx.count.framing_errors < before.framing_errors) {
            abort();
        }
    }
    cobs_roundtrip(data, size);
    return 0;
}
