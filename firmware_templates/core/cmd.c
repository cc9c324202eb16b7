/* cmd.c - see cmd.h. Messages and their fields are defined in proleg/protocol/definition.py. */
#include "cmd.h"

#include "app.h"

#include <stddef.h>
#include <string.h>

#include "drive.h"
#include "fault.h"
#include "uart.h"
#include "imucheck.h"
#include "limbmap.h"
#include "level.h"
#include "param.h"
#include "proto.h"
#include "rom.h"
#include "seq.h"
#include "safety.h"
#include "sma.h"
#include "telemetry.h"
#include "tx.h"

#define RX_BYTES_PER_TICK (2u * PROTO_MAX_ENCODED)

static proto_rx_t rx;

#define msg tx_msg /* the command being handled, then each reply (fields read first) */

/* One handler per command of the protocol definition (proto_gen.h's PROTO_COMMANDS):
 * a command added there does not compile until its cmd_<name>(void) is written here
 * (the command's token and id: `cur`). */
#define DECLARE_HANDLER(id, handler) static void handler(void);
PROTO_COMMANDS(DECLARE_HANDLER)

/* The command being handled (handle_command): its ACK and NACK take its token and id from
 * here, one copy of the argument set-up instead of one per reply site. */
static struct {
    uint8_t token, id;
} cur;

static void ack(void)
{
    tx_ack(cur.token, cur.id);
}

static void nack(uint8_t error, uint16_t detail)
{
    tx_nack(cur.token, cur.id, error, detail);
}

/* INFO's fields that are fixed at build time, in ROM: cmd_send_info copies the whole
 * struct and fills in the token and the telemetry rate. */
#define INFO_GAITS (CFG_N_GAITS_PX + CFG_N_GAITS_MX)
static const proto_info_t info_rom ROM = {
    0, PROTO_VERSION, CFG_BUILD_ID, CFG_GAIT_TABLE_HASH, CFG_ROBOT_NAME_INFO, CFG_BOARD_NAME_INFO,
    CFG_N_LIMBS, CFG_N_ACTUATORS, (uint8_t)(INFO_GAITS > 255u ? 255u : INFO_GAITS),
    CFG_MAX_LOADED_STEPS, (uint16_t)CFG_TICK_HZ, 0};

void cmd_send_info(uint8_t token)
{
    ROM_COPY(&msg.u.info, &info_rom, sizeof info_rom);
    msg.id = PROTO_ID_INFO;
    msg.u.info.token = token;
    msg.u.info.telemetry_hz = telemetry_rate();
    tx_send();
}

static void cmd_get_info(void)
{
    cmd_send_info(cur.token);
}

static void cmd_get_stats(void)
{
    const tx_counts_t *c = tx_counts();
    msg.id = PROTO_ID_STATS;
    msg.u.stats.token = cur.token;
    /* rx_ok..bad_value are proto_counters_t's fields and nacks..tx_dropped tx_counts_t's,
     * in the same order (checked below): one copy each. */
    memcpy(&msg.u.stats.rx_ok, &rx.count, sizeof rx.count);
    memcpy(&msg.u.stats.nacks, c, sizeof *c);
    msg.u.stats.tick_overruns = app_overruns();
    tx_send();
}

typedef char cmd_stats_layout_ok[(offsetof(proto_stats_t, bad_value) - offsetof(proto_stats_t, rx_ok) ==
                                   offsetof(proto_counters_t, bad_value) &&
                                   sizeof(proto_counters_t) == 6u * sizeof(uint32_t) &&
                                   offsetof(proto_stats_t, tx_dropped) - offsetof(proto_stats_t, nacks) ==
                                   offsetof(tx_counts_t, tx_dropped) &&
                                   sizeof(tx_counts_t) == 3u * sizeof(uint32_t)) ? 1 : -1];

static void cmd_start(void)
{
    uint8_t gait = msg.u.start.gait, index = gait;
    uint8_t dir = msg.u.start.direction, sdir;
    int8_t r;
    if (sma_estopped()) {
        nack(PROTO_ERR_ESTOP_LATCHED, 0);
        return;
    }
    if (fault_latched() || imucheck_measured() == IMUCHECK_UNKNOWN) {
        /* safety: no gait from an unknown state (before the first reading, or an IMU bad):
         * its step, the ground it levels on and the climb guard all need the limbs' angles */
        nack(PROTO_ERR_NOT_ALLOWED, fault_latched() ? 0 : 2);
        return;
    }
    if (seq_running()) { /* safety: a restart would restart the step; STOP first */
        nack(PROTO_ERR_NOT_ALLOWED, 1);
        return;
    }
    if (dir > PROTO_DIR_MINUS_X && (dir != PROTO_DIR_UNSTATED || gait != PROTO_GAIT_USER)) {
        nack(PROTO_ERR_OUT_OF_RANGE, 2); /* +x, -x, or (the loaded gait only) unstated */
        return;
    }
    if (gait == PROTO_GAIT_USER) {
        sdir = SEQ_DIR_LOADED;
        index = 0;
    } else {
        sdir = dir == PROTO_DIR_PLUS_X ? SEQ_DIR_PX : SEQ_DIR_MX;
    }
    if (gait != PROTO_GAIT_USER && limbmap_lost() != LIMBMAP_NONE && index < seq_gait_count(sdir)) {
        /* safety: a built-in gait needs the coil the fallback gave up, which stays given up until
         * the operator takes it back (SET_ACTUATOR_MAP with no entries, limbmap.h): restarted by a
         * host, it was heated up to the state timeout again at every START, and fell back again.
         * Only for a gait the board has (else NO_GAIT, below), and before seq_start: a refused
         * START leaves the sequencer as it was. */
        nack(PROTO_ERR_NOT_ALLOWED, 3);
        return;
    }
    r = seq_start(sdir, index, imucheck_measured());
    if (r != SEQ_OK) {
        nack(PROTO_ERR_NO_GAIT, gait);
        return; /* refused: nothing changed, the ground in use included */
    }
    level_at_start(); /* started from rest: level on this ground (level.h) */
#ifdef CFG_MAX_CLIMB_CDEG
    /* the climb guard: a built-in gait's way, or the one START states for a loaded gait */
    if (dir <= PROTO_DIR_MINUS_X) {
        uint16_t climb = level_too_steep(dir == PROTO_DIR_MINUS_X, gait);
        if (climb) {
            seq_stop(); /* refused before any coil heats (the ground just levelled on stays in use) */
            nack(PROTO_ERR_TOO_STEEP, climb);
            return;
        }
    }
#endif
    drive_started(gait, dir);
    fault_watchdog_rearm();
    ack();
    tx_event(PROTO_EV_GAIT_STARTED, gait, dir);
}

static void cmd_load_gait(void)
{
    cfg_state_t states[PROTO_MAX_GAIT_STEPS];
    uint8_t n = msg.u.load_gait.states_count;
    uint16_t bad = 0;
    uint8_t i;
    int8_t r;
    if (seq_running()) {
        nack(PROTO_ERR_NOT_ALLOWED, 0);
        return;
    }
    if (n > PROTO_MAX_GAIT_STEPS) {
        nack(PROTO_ERR_TOO_LONG, n);
        return;
    }
    for (i = 0; i < n; i++) {
        if (msg.u.load_gait.states[i] >= CFG_N_STATES) {
            nack(PROTO_ERR_OUT_OF_RANGE, i);
            return;
        }
        states[i] = (cfg_state_t)msg.u.load_gait.states[i];
    }
    r = seq_load(states, n, &bad);
    if (r == SEQ_ERR_FORBIDDEN) {
        nack(PROTO_ERR_FORBIDDEN_TRANSITION, bad);
    } else if (r != SEQ_OK) { /* SEQ_ERR_LENGTH: every state was checked above (no SEQ_ERR_STATE) */
        nack(n > CFG_MAX_LOADED_STEPS ? PROTO_ERR_TOO_LONG : PROTO_ERR_OUT_OF_RANGE, n);
    } else {
        ack();
        tx_event(PROTO_EV_GAIT_LOADED, 0, n);
    }
}

static void cmd_clear(void)
{
    uint8_t what = msg.u.clear.what;
    uint8_t done = 0;
    uint8_t i, bad;
    if (what & PROTO_CLEAR_COUNTERS) {
        memset(&rx.count, 0, sizeof rx.count);
        tx_clear_counts();
        app_clear_overruns();
        done |= PROTO_CLEAR_COUNTERS;
    }
    if ((what & PROTO_CLEAR_ESTOP) && sma_estopped()) {
        sma_clear_estop();
        done |= PROTO_CLEAR_ESTOP;
    }
    ack();
    if ((what & PROTO_CLEAR_FAULTS) && fault_latched()) {
        bad = imucheck_take_bad();
        fault_clear();
        guard_ack(); /* safety: the operator acknowledged; the thermal budget is not refunded */
        done |= PROTO_CLEAR_FAULTS;
        for (i = 0; i < CFG_N_LIMBS; i++) {
            if (bad & (1u << i)) {
                imucheck_start(i); /* faults again at once if it still does not answer */
            }
        }
    }
    if (done) { /* one event, after the restarts: imucheck_start sends nothing (its IMU answers, or
                 * faults again, in a later tick) */
        tx_event(PROTO_EV_FAULT_CLEARED, done, 0);
    }
}

static void cmd_estop(void)
{
    sma_estop(); /* first: every MOSFET off now */
    ack();
    tx_event(PROTO_EV_ESTOP, 0, 0);
    fault_stop_gait(PROTO_STOP_ESTOP);
}

static void cmd_ping(void)
{
    ack();
}

static void cmd_stop(void)
{
    sma_all_off();
    ack();
    fault_stop_gait(PROTO_STOP_COMMAND);
}

static void cmd_set_param(void)
{
    uint8_t r = param_set(msg.u.set_param.param, msg.u.set_param.index, msg.u.set_param.value);
    if (r) {
        nack(r, msg.u.set_param.param);
    } else {
        /* safety: what heated before made no progress towards a target read with what changed
         * (a threshold moved each step made every step "reached": docs/safety.md) */
        guard_started();
        ack();
    }
}

static void cmd_set_telemetry_rate(void)
{
    if (telemetry_set_rate(msg.u.set_telemetry_rate.hz) != 0u) {
        nack(PROTO_ERR_OUT_OF_RANGE, 0);
    } else {
        ack();
    }
}

static void cmd_set_actuator_map(void)
{
    uint16_t bad = 0;
    uint8_t r;
    if (seq_running()) {
        nack(PROTO_ERR_NOT_ALLOWED, 0);
        return;
    }
    r = limbmap_set(msg.u.set_actuator_map.actuators, msg.u.set_actuator_map.actuators_count, &bad);
    if (r) {
        nack(r, bad);
    } else {
        ack();
    }
}

static void cmd_get_actuator_map(void)
{
    uint8_t i;
    msg.id = PROTO_ID_ACTUATOR_MAP;
    msg.u.actuator_map.token = cur.token;
    msg.u.actuator_map.lost = limbmap_lost();
    msg.u.actuator_map.actuators_count = CFG_N_LIMBS;
    for (i = 0; i < CFG_N_LIMBS; i++) {
        msg.u.actuator_map.actuators[i] = limbmap_actuator(i);
    }
    tx_send();
}

/* Level calibration (level.h): only with every coil off and no gait, so the robot is at rest. */
static void cmd_calibrate_level(void)
{
    uint8_t why = seq_running() ? 1u : imucheck_bad() ? 2u : fault_latched() ? 3u : 0u;
    int8_t r;
    if (msg.u.calibrate_level.ground > 1u) {
        nack(PROTO_ERR_OUT_OF_RANGE, 1u); /* field 1: ground is 0 (flat) or 1 (this ground) */
        return;
    }
    if (why == 0u) {
        r = level_calibrate(msg.u.calibrate_level.ground);
        why = r < 0 ? (uint8_t)(3 - r) : 0u; /* -1 under way (4), -2 not in this build (5), -3 not at rest since a gait (6) */
    }
    if (why) {
        nack(PROTO_ERR_NOT_ALLOWED, why);
    } else {
        ack();
    }
}

static void cmd_get_level(void)
{
    uint8_t i;
    msg.id = PROTO_ID_LEVEL;
    msg.u.level.token = cur.token;
    msg.u.level.status = level_status();
    msg.u.level.offset_count = CFG_N_LIMBS;
    msg.u.level.ground_count = CFG_N_LIMBS;
    for (i = 0; i < CFG_N_LIMBS; i++) {
        msg.u.level.offset[i] = level_offset_cdeg(i);
        msg.u.level.ground[i] = level_ground_cdeg(i);
    }
    tx_send();
}

static void cmd_clear_level(void)
{
    int8_t r = seq_running() ? -1 : level_clear();
    if (r != 0) {
        nack(PROTO_ERR_NOT_ALLOWED, r == -2 ? 5u : 0u);
    } else {
        ack();
    }
}

static void handle_command(void)
{
    cur.token = PROTO_CMD_TOKEN(&msg);
    cur.id = msg.id;
    switch (msg.id) {
#define DISPATCH(id, handler) \
    case id:                  \
        handler();            \
        break;
        PROTO_COMMANDS(DISPATCH)
    default: /* a robot->host message sent to the robot */
        nack(PROTO_ERR_UNKNOWN_MESSAGE, 0);
        break;
    }
}

void cmd_init(uint8_t kept)
{
    proto_rx_init(&rx);
    level_init(kept);
}

void cmd_poll(void)
{
    uint8_t n; /* RX_BYTES_PER_TICK = 132 fits */
    level_poll();
    for (n = 0; n < RX_BYTES_PER_TICK; n++) {
        int c = uart_read_byte();
        if (c < 0) {
            break;
        }
        if (proto_rx_byte(&rx, (uint8_t)c, &msg)) {
            fault_heard_host();
            handle_command();
        } else if (rx.rej_error) {
            tx_nack(rx.rej_token, rx.rej_id, rx.rej_error, 0);
        }
    }
}
