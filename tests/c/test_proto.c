/* test_proto.c - host driver for the C protocol runtime, run by tests/test_protocol_c.py.
 *
 *   test_proto stream    feed stdin byte by byte to proto_rx_byte; per decoded message print
 *                        "M <hex of proto_encode(msg)>", per refused CRC-valid frame
 *                        "R <id> <token> <error>", at EOF "C <frames_ok> <crc_errors>
 *                        <framing_errors> <unknown_ids> <bad_length> <bad_value>"
 *   test_proto emit      print "M <hex>" for messages built field by field in C (their
 *                        values are mirrored in proleg.protocol.vectors.C_ENCODED)
 *   test_proto selftest  CRC check value, COBS corner cases, encode/pack refusals; exit 1 on failure
 */
#include <stdio.h>
#include <string.h>

#include "cobs.h"
#include "crc16.h"
#include "proto.h"

static void print_frame(const proto_msg_t *m)
{
    uint8_t out[PROTO_MAX_ENCODED];
    size_t n = proto_encode(m, out, sizeof out), i;
    printf("M ");
    for (i = 0; i < n; i++) {
        printf("%02x", out[i]);
    }
    printf("\n");
}

static int run_stream(void)
{
    static proto_rx_t rx;
    proto_msg_t m;
    int c;
    proto_rx_init(&rx);
    while ((c = getchar()) != EOF) {
        if (proto_rx_byte(&rx, (uint8_t)c, &m)) {
            print_frame(&m);
        } else if (rx.rej_error) {
            printf("R %u %u %u\n", rx.rej_id, rx.rej_token, rx.rej_error);
        }
    }
    printf("C %lu %lu %lu %lu %lu %lu\n", (unsigned long)rx.count.frames_ok,
           (unsigned long)rx.count.crc_errors, (unsigned long)rx.count.framing_errors,
           (unsigned long)rx.count.unknown_ids, (unsigned long)rx.count.bad_length,
           (unsigned long)rx.count.bad_value);
    return 0;
}

static int run_emit(void)
{
    proto_msg_t m;
    memset(&m, 0, sizeof m);
    m.id = PROTO_ID_TELEMETRY;
    m.u.telemetry.seq = 65535u;
    m.u.telemetry.time_ms = 4000000000ul;
    m.u.telemetry.measured = 2;
    m.u.telemetry.target = 3;
    m.u.telemetry.gait = PROTO_GAIT_USER;
    m.u.telemetry.direction = PROTO_DIR_MINUS_X;
    m.u.telemetry.step = 1;
    m.u.telemetry.flags = PROTO_FLAG_RUNNING | PROTO_FLAG_USER_GAIT;
    m.u.telemetry.psi_count = 2;
    m.u.telemetry.psi[0] = -2050;
    m.u.telemetry.psi[1] = 3000;
    m.u.telemetry.duty_count = 2;
    m.u.telemetry.duty[0] = 6000;
    m.u.telemetry.duty[1] = 0;
    print_frame(&m);

    memset(&m, 0, sizeof m);
    m.id = PROTO_ID_INFO;
    m.u.info.protocol_version = PROTO_VERSION;
    m.u.info.build_id = 0xDEADBEEFul;
    m.u.info.gait_hash = 0x01020304ul;
    strcpy(m.u.info.robot_name, "paper-r1");
    strcpy(m.u.info.board, "arduino-nano");
    m.u.info.limbs = 2;
    m.u.info.actuators = 2;
    m.u.info.gaits = 4;
    m.u.info.max_gait_steps = PROTO_MAX_GAIT_STEPS;
    m.u.info.tick_hz = 1000;
    m.u.info.telemetry_hz = 50;
    print_frame(&m);

    memset(&m, 0, sizeof m);
    m.id = PROTO_ID_NACK;
    m.u.nack.token = 7;
    m.u.nack.cmd = PROTO_ID_LOAD_GAIT;
    m.u.nack.error = PROTO_ERR_FORBIDDEN_TRANSITION;
    m.u.nack.detail = 3;
    print_frame(&m);

    memset(&m, 0, sizeof m);
    m.id = PROTO_ID_EVENT;
    m.u.event.time_ms = 123456ul;
    m.u.event.kind = PROTO_EV_FAULT;
    m.u.event.code = PROTO_FAULT_STATE_TIMEOUT;
    m.u.event.detail = 1;
    print_frame(&m);

    memset(&m, 0, sizeof m);
    m.id = PROTO_ID_STATS;
    m.u.stats.token = 9;
    m.u.stats.rx_ok = 100000ul;
    m.u.stats.crc_errors = 1;
    m.u.stats.framing_errors = 2;
    m.u.stats.unknown_ids = 3;
    m.u.stats.bad_length = 4;
    m.u.stats.bad_value = 5;
    m.u.stats.nacks = 6;
    m.u.stats.tx_frames = 7;
    m.u.stats.tx_dropped = 8;
    m.u.stats.tick_overruns = 9;
    print_frame(&m);

    memset(&m, 0, sizeof m);
    m.id = PROTO_ID_SET_PARAM;
    m.u.set_param.token = 255;
    m.u.set_param.param = PROTO_PARAM_PSI_STAR_CDEG;
    m.u.set_param.index = 1;
    m.u.set_param.value = -2147483647l - 1;
    print_frame(&m);

    memset(&m, 0, sizeof m);
    m.id = PROTO_ID_SET_ACTUATOR_MAP;
    m.u.set_actuator_map.token = 16;
    m.u.set_actuator_map.actuators_count = 2;
    m.u.set_actuator_map.actuators[0] = 0;
    m.u.set_actuator_map.actuators[1] = 0;
    print_frame(&m);

    memset(&m, 0, sizeof m);
    m.id = PROTO_ID_ACTUATOR_MAP;
    m.u.actuator_map.token = 19;
    m.u.actuator_map.lost = 1;
    m.u.actuator_map.actuators_count = 2;
    m.u.actuator_map.actuators[0] = 1;
    m.u.actuator_map.actuators[1] = 0;
    print_frame(&m);

    memset(&m, 0, sizeof m);
    m.id = PROTO_ID_EVENT;
    m.u.event.time_ms = 20000ul;
    m.u.event.kind = PROTO_EV_SUSPECT;
    m.u.event.code = 1;
    m.u.event.detail = 2u * 4u + 3u;
    print_frame(&m);

    memset(&m, 0, sizeof m);
    m.id = PROTO_ID_LEVEL;
    m.u.level.token = 17;
    m.u.level.status = PROTO_LEVEL_STORED;
    m.u.level.offset_count = 2;
    m.u.level.offset[0] = 312;
    m.u.level.offset[1] = -2000;
    m.u.level.ground_count = 2;
    m.u.level.ground[0] = -995;
    m.u.level.ground[1] = 1003;
    print_frame(&m);

    memset(&m, 0, sizeof m);
    m.id = PROTO_ID_EVENT;
    m.u.event.time_ms = 70000ul;
    m.u.event.kind = PROTO_EV_LEVEL_DONE;
    m.u.event.code = PROTO_LEVEL_RES_TOO_TILTED;
    m.u.event.detail = 2;
    print_frame(&m);
    return 0;
}

#define CHECK(cond)                                                      \
    do {                                                                 \
        if (!(cond)) {                                                   \
            printf("FAIL %s:%d: %s\n", __FILE__, __LINE__, #cond);       \
            return 1;                                                    \
        }                                                                \
    } while (0)

static int run_selftest(void)
{
    static const uint8_t check[] = "123456789";
    uint8_t buf[PROTO_MAX_ENCODED];
    proto_msg_t m;
    cobs_dec_t d;
    uint8_t o;

    CHECK(crc16_ccitt(CRC16_INIT, check, 9) == 0x29B1);
    /* COBS: 11 00 -> 02 11 01 ; 00 -> 01 01 ; empty -> 01 */
    buf[1] = 0x11; buf[2] = 0x00;
    CHECK(cobs_encode_inplace(buf, 2) == 3 && buf[0] == 2 && buf[1] == 0x11 && buf[2] == 1);
    buf[1] = 0x00;
    CHECK(cobs_encode_inplace(buf, 1) == 2 && buf[0] == 1 && buf[1] == 1);
    CHECK(cobs_encode_inplace(buf, 0) == 1 && buf[0] == 1);
    CHECK(cobs_encode_inplace(buf, 254) == 0);
    cobs_dec_reset(&d);
    CHECK(!cobs_dec_complete(&d));
    CHECK(cobs_dec_byte(&d, 3, &o) == 0 && !cobs_dec_complete(&d));
    CHECK(cobs_dec_byte(&d, 0x22, &o) == 1 && o == 0x22 && !cobs_dec_complete(&d));
    CHECK(cobs_dec_byte(&d, 0x33, &o) == 1 && o == 0x33 && cobs_dec_complete(&d));
    CHECK(cobs_dec_byte(&d, 1, &o) == 1 && o == 0 && cobs_dec_complete(&d));

    /* refusals: unknown id, count above max, buffer too small */
    memset(&m, 0, sizeof m);
    m.id = 0x7F;
    CHECK(proto_encode(&m, buf, sizeof buf) == 0);
    m.id = PROTO_ID_TELEMETRY;
    m.u.telemetry.psi_count = PROTO_MAX_LIMBS + 1;
    CHECK(proto_encode(&m, buf, sizeof buf) == 0);
    m.u.telemetry.psi_count = PROTO_MAX_LIMBS;
    m.u.telemetry.duty_count = PROTO_MAX_CHANNELS;
    CHECK(proto_encode(&m, buf, sizeof buf) > 0);
    CHECK(proto_encode(&m, buf, 10) == 0);
    CHECK(proto_encode(&m, buf, 3) == 0);
    m.id = PROTO_ID_PING;
    m.u.ping.token = 0;
    CHECK(proto_encode(&m, buf, 6) == 6 && buf[5] == 0); /* 01 00 crc crc -> 6 bytes on the wire */
    CHECK(proto_encode(&m, buf, 5) == 0);
    CHECK(proto_unpack(buf, 0, &m) == PROTO_ERR_UNKNOWN_MESSAGE);
    printf("OK\n");
    return 0;
}

int main(int argc, char **argv)
{
    if (argc == 2 && strcmp(argv[1], "stream") == 0) {
        return run_stream();
    }
    if (argc == 2 && strcmp(argv[1], "emit") == 0) {
        return run_emit();
    }
    if (argc == 2 && strcmp(argv[1], "selftest") == 0) {
        return run_selftest();
    }
    fprintf(stderr, "usage: test_proto stream|emit|selftest\n");
    return 2;
}
