/* app.c - see app.h. Messages and their fields are defined in proleg/protocol/definition.py. */
#include "app.h"

#include <string.h>

#include "ctl.h"
#include "hal.h"
#include "mpu6050.h"
#include "proto.h"
#include "psi.h"
#include "rom.h"
#include "seq.h"
#include "sma.h"

#if CFG_N_LIMBS > 8
#error "at most 8 limbs (one bit per limb in the IMU fault mask)"
#endif

#define RX_BYTES_PER_TICK (2u * PROTO_MAX_ENCODED)
#define STATE_UNKNOWN 0xFFFFu

/* Telemetry may use at most half the link (UART bytes/s = baud/10), so that replies and
 * events always find room in the transmit queue: a faster SET_TELEMETRY_RATE is NACKed.
 * Wire bytes of one TELEMETRY frame: 15 fixed + 2 counts + 2/limb + 2/actuator + CRC 2
 * + COBS overhead 1 + delimiter 1 (rounded up to 24 fixed). */
#define TELEMETRY_WIRE_BYTES (24UL + 2UL * CFG_N_LIMBS + 2UL * CFG_N_ACTUATORS)
#define TELEMETRY_LINK_HZ (CFG_UART_BAUD / 10UL / TELEMETRY_WIRE_BYTES / 2UL)
#define TELEMETRY_MAX_HZ (TELEMETRY_LINK_HZ < CFG_TICK_HZ ? TELEMETRY_LINK_HZ : CFG_TICK_HZ)

/* |g|² plausibility band, 0.5 g .. 1.5 g, in LSB². */
#define G2_MIN ((uint32_t)(MPU6050_ACCEL_LSB_PER_G / 2) * (uint32_t)(MPU6050_ACCEL_LSB_PER_G / 2))
#define G2_MAX ((uint32_t)(3 * MPU6050_ACCEL_LSB_PER_G / 2) * (uint32_t)(3 * MPU6050_ACCEL_LSB_PER_G / 2))
#define MAX_PARAM_MS 600000L

static const uint8_t imu_addr[CFG_N_LIMBS] ROM = CFG_LIMB_IMU_ADDR;
static const char robot_name[] ROM = CFG_ROBOT_NAME;
static const char board_name[] ROM = CFG_BOARD_NAME;

static proto_rx_t rx;
static proto_msg_t msg; /* the command being handled, then each reply (fields read first) */
static uint8_t txbuf[PROTO_MAX_ENCODED];

static struct {
    uint32_t ms;            /* firmware time */
    uint16_t us_acc;
    uint8_t fault;          /* a fault is latched */
    uint8_t imu_bad;        /* bit per limb: IMU faulted, not read until CLEAR(FAULTS) */
    uint8_t imu_err[CFG_N_LIMBS];
    uint16_t stuck[CFG_N_LIMBS];
    mpu6050_accel_t last[CFG_N_LIMBS];
    uint32_t measured;      /* debounced robot state, STATE_UNKNOWN until every limb has one */
    uint8_t gait, dir;      /* gait last started */
    uint16_t drive_pm, hold_pm;
    uint32_t max_on_ticks, cooldown_ticks;
    uint32_t watchdog_ticks, since_rx;
    uint8_t watchdog_tripped;
    uint16_t telem_hz, telem_acc, telem_seq;
    uint8_t clamped;
    uint8_t pending_delim;  /* a frame went out half: start the next with a delimiter */
    uint32_t nacks, tx_frames, tx_dropped;
} st;

/* ------------------------------------------------------------------ sending */

static void send(void)
{
    size_t n = proto_encode(&msg, txbuf, sizeof txbuf);
    uint16_t w;
    if (n == 0u) {
        st.tx_dropped++;
        return;
    }
    if (st.pending_delim) {
        uint8_t zero = 0;
        if (hal_uart_write(&zero, 1) != 1u) {
            st.tx_dropped++;
            return;
        }
        st.pending_delim = 0;
    }
    w = hal_uart_write(txbuf, (uint16_t)n);
    if (w == n) {
        st.tx_frames++;
    } else {
        st.tx_dropped++;
        st.pending_delim = (uint8_t)(w > 0u);
    }
}

static void send_event(uint8_t kind, uint8_t code, uint16_t detail)
{
    msg.id = PROTO_ID_EVENT;
    msg.u.event.time_ms = st.ms;
    msg.u.event.kind = kind;
    msg.u.event.code = code;
    msg.u.event.detail = detail;
    send();
}

static void send_ack(uint8_t token, uint8_t cmd)
{
    msg.id = PROTO_ID_ACK;
    msg.u.ack.token = token;
    msg.u.ack.cmd = cmd;
    send();
}

static void send_nack(uint8_t token, uint8_t cmd, uint8_t error, uint16_t detail)
{
    st.nacks++;
    msg.id = PROTO_ID_NACK;
    msg.u.nack.token = token;
    msg.u.nack.cmd = cmd;
    msg.u.nack.error = error;
    msg.u.nack.detail = detail;
    send();
}

static void copy_rom_text(char *dst, const char *src, uint8_t cap)
{
    uint8_t i = 0;
    char c;
    while (i + 1u < cap && (c = (char)ROM_U8(&src[i])) != '\0') {
        dst[i++] = c;
    }
    while (i < cap) {
        dst[i++] = '\0';
    }
}

static void send_info(uint8_t token)
{
    uint16_t gaits = (uint16_t)(CFG_N_GAITS_PX + CFG_N_GAITS_MX);
    msg.id = PROTO_ID_INFO;
    msg.u.info.token = token;
    msg.u.info.protocol_version = PROTO_VERSION;
    msg.u.info.build_id = CFG_BUILD_ID;
    msg.u.info.gait_hash = CFG_GAIT_TABLE_HASH;
    copy_rom_text(msg.u.info.robot_name, robot_name, PROTO_ROBOT_NAME_LEN);
    copy_rom_text(msg.u.info.board, board_name, PROTO_BOARD_NAME_LEN);
    msg.u.info.limbs = CFG_N_LIMBS;
    msg.u.info.actuators = CFG_N_ACTUATORS;
    msg.u.info.gaits = (uint8_t)(gaits > 255u ? 255u : gaits);
    msg.u.info.max_gait_steps = CFG_MAX_LOADED_STEPS;
    msg.u.info.tick_hz = (uint16_t)CFG_TICK_HZ;
    msg.u.info.telemetry_hz = st.telem_hz;
    send();
}

static void send_stats(uint8_t token)
{
    msg.id = PROTO_ID_STATS;
    msg.u.stats.token = token;
    msg.u.stats.rx_ok = rx.count.frames_ok;
    msg.u.stats.crc_errors = rx.count.crc_errors;
    msg.u.stats.framing_errors = rx.count.framing_errors;
    msg.u.stats.unknown_ids = rx.count.unknown_ids;
    msg.u.stats.bad_length = rx.count.bad_length;
    msg.u.stats.bad_value = rx.count.bad_value;
    msg.u.stats.nacks = st.nacks;
    msg.u.stats.tx_frames = st.tx_frames;
    msg.u.stats.tx_dropped = st.tx_dropped;
    send();
}

static uint16_t flags(void)
{
    uint16_t f = 0;
    uint8_t i;
    if (seq_running()) {
        f |= PROTO_FLAG_RUNNING;
    }
    if (seq_holding()) {
        f |= PROTO_FLAG_HOLDING;
    }
    if (st.fault) {
        f |= PROTO_FLAG_FAULT;
    }
    if (sma_estopped()) {
        f |= PROTO_FLAG_ESTOP;
    }
    for (i = 0; i < CFG_N_ACTUATORS; i++) {
        if (sma_cooling(i)) {
            f |= PROTO_FLAG_COOLDOWN;
        }
    }
    if (st.clamped) {
        f |= PROTO_FLAG_DUTY_CLAMPED;
    }
    if (st.imu_bad) {
        f |= PROTO_FLAG_IMU_FAULT;
    }
    if (st.watchdog_tripped) {
        f |= PROTO_FLAG_LINK_WATCHDOG;
    }
    if (seq_gait_count(SEQ_DIR_LOADED)) {
        f |= PROTO_FLAG_USER_GAIT;
    }
    if (st.measured == STATE_UNKNOWN) {
        f |= PROTO_FLAG_STATE_UNKNOWN;
    }
    return f;
}

static void send_telemetry(void)
{
    uint8_t i;
    uint16_t step = seq_step();
    msg.id = PROTO_ID_TELEMETRY;
    msg.u.telemetry.seq = st.telem_seq++;
    msg.u.telemetry.time_ms = st.ms;
    msg.u.telemetry.measured = (uint16_t)st.measured;
    msg.u.telemetry.target = (uint16_t)seq_target();
    msg.u.telemetry.gait = st.gait;
    msg.u.telemetry.direction = st.dir;
    msg.u.telemetry.step = (uint8_t)(step > 255u ? 255u : step);
    msg.u.telemetry.flags = flags();
    msg.u.telemetry.psi_count = CFG_N_LIMBS;
    for (i = 0; i < CFG_N_LIMBS; i++) {
        msg.u.telemetry.psi[i] = psi_last_centideg(i); /* atan2 only here, at telemetry rate */
    }
    msg.u.telemetry.duty_count = CFG_N_ACTUATORS;
    for (i = 0; i < CFG_N_ACTUATORS; i++) {
        msg.u.telemetry.duty[i] = sma_duty(i);
    }
    st.clamped = 0;
    send();
}

/* ------------------------------------------------------------------ stopping and faults */

static void stop_gait(uint8_t reason)
{
    uint32_t cycles = seq_cycles();
    if (!seq_running()) {
        return;
    }
    seq_stop();
    send_event(PROTO_EV_GAIT_STOPPED, reason, (uint16_t)(cycles > 0xFFFFu ? 0xFFFFu : cycles));
}

static void fault(uint8_t code, uint16_t detail)
{
    sma_all_off();
    st.fault = 1;
    send_event(PROTO_EV_FAULT, code, detail);
    stop_gait(PROTO_STOP_FAULT);
}

static void imu_fault(uint8_t limb, uint8_t code)
{
    st.imu_bad = (uint8_t)(st.imu_bad | (1u << limb));
    fault(code, limb);
}

static void imu_start(uint8_t limb)
{
    int8_t r = mpu6050_init(ROM_U8(&imu_addr[limb]));
    st.imu_err[limb] = 0;
    st.stuck[limb] = 0;
    if (r == MPU6050_ERR_BUS) {
        imu_fault(limb, PROTO_FAULT_IMU_NO_ACK);
    } else if (r != MPU6050_OK) {
        imu_fault(limb, PROTO_FAULT_IMU_BAD_DATA);
    }
}

/* ------------------------------------------------------------------ time */

static uint32_t ms_to_ticks(uint32_t ms)
{
    return (ms / 1000u) * CFG_TICK_HZ + ((ms % 1000u) * CFG_TICK_HZ + 999u) / 1000u;
}

/* ------------------------------------------------------------------ commands */

/* Where threshold `flat` (limb by limb, thresholds in order) lives. */
static int8_t threshold_at(uint8_t flat, uint8_t *limb, uint8_t *thr)
{
    uint8_t i;
    for (i = 0; i < CFG_N_LIMBS; i++) {
        uint8_t n = (uint8_t)(psi_levels(i) - 1u);
        if (flat < n) {
            *limb = i;
            *thr = flat;
            return 0;
        }
        flat = (uint8_t)(flat - n);
    }
    return -1;
}

/* 0 when lo ≤ v ≤ hi and v ≤ safe; else OUT_OF_RANGE, or SAFETY_LIMIT past `safe`. */
static uint8_t check(int32_t v, int32_t lo, int32_t hi, int32_t safe)
{
    if (v < lo || v > hi) {
        return PROTO_ERR_OUT_OF_RANGE;
    }
    return v > safe ? PROTO_ERR_SAFETY_LIMIT : 0u;
}

#define ANY INT32_MAX

/* Returns 0 (accepted) or a PROTO_ERR_* code. */
static uint8_t set_param(uint8_t param, uint8_t index, int32_t v)
{
    uint8_t limb, thr, i, e;
    switch (param) {
    case PROTO_PARAM_DRIVE_DUTY:
    case PROTO_PARAM_HOLD_DUTY:
        if ((e = check(v, param == PROTO_PARAM_DRIVE_DUTY ? 1 : 0, ANY, (int32_t)sma_max_duty())) != 0u) {
            return e;
        }
        *(param == PROTO_PARAM_DRIVE_DUTY ? &st.drive_pm : &st.hold_pm) = (uint16_t)v;
        return 0;
    case PROTO_PARAM_HOLD_MS:
        if ((e = check(v, 0, MAX_PARAM_MS, ANY)) != 0u) {
            return e;
        }
        seq_set_hold(ms_to_ticks((uint32_t)v));
        return 0;
    case PROTO_PARAM_DEBOUNCE_TICKS:
        if ((e = check(v, 1, 1000, ANY)) != 0u) {
            return e;
        }
        psi_set_debounce((uint16_t)v);
        return 0;
    case PROTO_PARAM_STATE_TIMEOUT_MS:
        if ((e = check(v, 1, ANY, CFG_STATE_TIMEOUT_MS)) != 0u) {
            return e;
        }
        seq_set_timeout(ms_to_ticks((uint32_t)v));
        return 0;
    case PROTO_PARAM_PSI_STAR_CDEG:
        if (threshold_at(index, &limb, &thr) != 0 || check(v, -8999, 8999, ANY) != 0u ||
            psi_set_band(limb, thr, (int16_t)v, psi_hyst_cdeg(limb, thr)) != 0) {
            return PROTO_ERR_OUT_OF_RANGE;
        }
        return 0;
    case PROTO_PARAM_HYSTERESIS_CDEG:
        if (index >= CFG_N_LIMBS || check(v, 0, 2000, ANY) != 0u) {
            return PROTO_ERR_OUT_OF_RANGE;
        }
        for (i = 0; i + 1u < psi_levels(index); i++) {
            if (psi_set_band(index, i, psi_star_cdeg(index, i), (int16_t)v) != 0) {
                return PROTO_ERR_OUT_OF_RANGE; /* earlier thresholds keep the new width */
            }
        }
        return 0;
    case PROTO_PARAM_MAX_ON_MS:
        if ((e = check(v, 1, ANY, CFG_MAX_ON_MS)) != 0u) {
            return e;
        }
        if (sma_set_limits(sma_max_duty(), ms_to_ticks((uint32_t)v), st.cooldown_ticks) != 0) {
            return PROTO_ERR_SAFETY_LIMIT;
        }
        st.max_on_ticks = ms_to_ticks((uint32_t)v);
        return 0;
    case PROTO_PARAM_MIN_COOLDOWN_MS:
        if ((e = check(v, 0, MAX_PARAM_MS, ANY)) != 0u) {
            return e;
        }
        if ((uint32_t)v < CFG_MIN_COOLDOWN_MS ||
            sma_set_limits(sma_max_duty(), st.max_on_ticks, ms_to_ticks((uint32_t)v)) != 0) {
            return PROTO_ERR_SAFETY_LIMIT;
        }
        st.cooldown_ticks = ms_to_ticks((uint32_t)v);
        return 0;
    case PROTO_PARAM_LINK_WATCHDOG_MS:
        if ((e = check(v, 0, MAX_PARAM_MS, ANY)) != 0u) {
            return e;
        }
        if (CFG_LINK_WATCHDOG_MS != 0u && (v == 0 || (uint32_t)v > CFG_LINK_WATCHDOG_MS)) {
            return PROTO_ERR_SAFETY_LIMIT;
        }
        st.watchdog_ticks = ms_to_ticks((uint32_t)v);
        return 0;
    default:
        return PROTO_ERR_OUT_OF_RANGE;
    }
}

static void cmd_start(uint8_t token)
{
    uint8_t gait = msg.u.start.gait;
    uint8_t dir = msg.u.start.direction;
    int8_t r;
    if (sma_estopped()) {
        send_nack(token, PROTO_ID_START, PROTO_ERR_ESTOP_LATCHED, 0);
        return;
    }
    if (st.fault) {
        send_nack(token, PROTO_ID_START, PROTO_ERR_NOT_ALLOWED, 0);
        return;
    }
    if (gait == PROTO_GAIT_USER) {
        r = seq_start(SEQ_DIR_LOADED, 0, st.measured);
    } else if (dir > PROTO_DIR_MINUS_X) {
        send_nack(token, PROTO_ID_START, PROTO_ERR_OUT_OF_RANGE, 2);
        return;
    } else {
        r = seq_start(dir == PROTO_DIR_PLUS_X ? SEQ_DIR_PX : SEQ_DIR_MX, gait, st.measured);
    }
    if (r != SEQ_OK) {
        send_nack(token, PROTO_ID_START, PROTO_ERR_NO_GAIT, gait);
        return;
    }
    st.gait = gait;
    st.dir = dir;
    st.watchdog_tripped = 0;
    send_ack(token, PROTO_ID_START);
    send_event(PROTO_EV_GAIT_STARTED, gait, dir);
}

static void cmd_load_gait(uint8_t token)
{
    cfg_state_t states[PROTO_MAX_GAIT_STEPS];
    uint8_t n = msg.u.load_gait.states_count;
    uint16_t bad = 0;
    uint8_t i;
    int8_t r;
    if (seq_running()) {
        send_nack(token, PROTO_ID_LOAD_GAIT, PROTO_ERR_NOT_ALLOWED, 0);
        return;
    }
    if (n > PROTO_MAX_GAIT_STEPS) {
        send_nack(token, PROTO_ID_LOAD_GAIT, PROTO_ERR_TOO_LONG, n);
        return;
    }
    for (i = 0; i < n; i++) {
        if (msg.u.load_gait.states[i] >= CFG_N_STATES) {
            send_nack(token, PROTO_ID_LOAD_GAIT, PROTO_ERR_OUT_OF_RANGE, i);
            return;
        }
        states[i] = (cfg_state_t)msg.u.load_gait.states[i];
    }
    r = seq_load(states, n, &bad);
    if (r == SEQ_ERR_FORBIDDEN) {
        send_nack(token, PROTO_ID_LOAD_GAIT, PROTO_ERR_FORBIDDEN_TRANSITION, bad);
    } else if (r == SEQ_ERR_LENGTH) {
        send_nack(token, PROTO_ID_LOAD_GAIT, n > CFG_MAX_LOADED_STEPS ? PROTO_ERR_TOO_LONG : PROTO_ERR_OUT_OF_RANGE, n);
    } else if (r != SEQ_OK) {
        send_nack(token, PROTO_ID_LOAD_GAIT, PROTO_ERR_OUT_OF_RANGE, bad);
    } else {
        send_ack(token, PROTO_ID_LOAD_GAIT);
        send_event(PROTO_EV_GAIT_LOADED, 0, n);
    }
}

static void cmd_clear(uint8_t token)
{
    uint8_t what = msg.u.clear.what;
    uint8_t done = 0;
    uint8_t i, bad;
    if (what & PROTO_CLEAR_COUNTERS) {
        memset(&rx.count, 0, sizeof rx.count);
        st.nacks = 0;
        st.tx_frames = 0;
        st.tx_dropped = 0;
        done |= PROTO_CLEAR_COUNTERS;
    }
    if ((what & PROTO_CLEAR_ESTOP) && sma_estopped()) {
        sma_clear_estop();
        done |= PROTO_CLEAR_ESTOP;
    }
    send_ack(token, PROTO_ID_CLEAR);
    if ((what & PROTO_CLEAR_FAULTS) && st.fault) {
        bad = st.imu_bad;
        st.fault = 0;
        st.imu_bad = 0;
        done |= PROTO_CLEAR_FAULTS;
        send_event(PROTO_EV_FAULT_CLEARED, done, 0);
        done = 0;
        for (i = 0; i < CFG_N_LIMBS; i++) {
            if (bad & (1u << i)) {
                imu_start(i); /* faults again at once if it still does not answer */
            }
        }
    }
    if (done) {
        send_event(PROTO_EV_FAULT_CLEARED, done, 0);
    }
}

static void handle_command(void)
{
    uint8_t token = PROTO_CMD_TOKEN(&msg);
    uint8_t r;
    switch (msg.id) {
    case PROTO_ID_ESTOP:
        sma_estop(); /* first: every MOSFET off now */
        send_ack(token, PROTO_ID_ESTOP);
        send_event(PROTO_EV_ESTOP, 0, 0);
        stop_gait(PROTO_STOP_ESTOP);
        break;
    case PROTO_ID_PING:
        send_ack(token, PROTO_ID_PING);
        break;
    case PROTO_ID_GET_INFO:
        send_info(token);
        break;
    case PROTO_ID_GET_STATS:
        send_stats(token);
        break;
    case PROTO_ID_START:
        cmd_start(token);
        break;
    case PROTO_ID_STOP:
        sma_all_off();
        send_ack(token, PROTO_ID_STOP);
        stop_gait(PROTO_STOP_COMMAND);
        break;
    case PROTO_ID_LOAD_GAIT:
        cmd_load_gait(token);
        break;
    case PROTO_ID_SET_PARAM:
        r = set_param(msg.u.set_param.param, msg.u.set_param.index, msg.u.set_param.value);
        if (r) {
            send_nack(token, PROTO_ID_SET_PARAM, r, msg.u.set_param.param);
        } else {
            send_ack(token, PROTO_ID_SET_PARAM);
        }
        break;
    case PROTO_ID_SET_TELEMETRY_RATE:
        if (msg.u.set_telemetry_rate.hz > TELEMETRY_MAX_HZ) {
            send_nack(token, PROTO_ID_SET_TELEMETRY_RATE, PROTO_ERR_OUT_OF_RANGE, 0);
        } else {
            st.telem_hz = msg.u.set_telemetry_rate.hz;
            st.telem_acc = 0;
            send_ack(token, PROTO_ID_SET_TELEMETRY_RATE);
        }
        break;
    case PROTO_ID_CLEAR:
        cmd_clear(token);
        break;
    default: /* a robot->host message sent to the robot */
        send_nack(token, msg.id, PROTO_ERR_UNKNOWN_MESSAGE, 0);
        break;
    }
}

static void poll_link(void)
{
    uint16_t n;
    for (n = 0; n < RX_BYTES_PER_TICK; n++) {
        int c = hal_uart_read_byte();
        if (c < 0) {
            break;
        }
        if (proto_rx_byte(&rx, (uint8_t)c, &msg)) {
            st.since_rx = 0;
            handle_command();
        } else if (rx.rej_error) {
            send_nack(rx.rej_token, rx.rej_id, rx.rej_error, 0);
        }
    }
}

/* ------------------------------------------------------------------ sensing */

static void read_imus(void)
{
    uint8_t levels[CFG_N_LIMBS];
    uint8_t i, known = 1;
    for (i = 0; i < CFG_N_LIMBS; i++) {
        mpu6050_accel_t a;
        uint32_t g2;
        if (st.imu_bad & (1u << i)) {
            known = 0;
            continue;
        }
        if (mpu6050_read_accel(ROM_U8(&imu_addr[i]), &a) != MPU6050_OK) {
            if (++st.imu_err[i] >= 2u) {
                imu_fault(i, PROTO_FAULT_IMU_NO_ACK);
            }
        } else {
            st.imu_err[i] = 0;
            if (a.ax == st.last[i].ax && a.ay == st.last[i].ay && a.az == st.last[i].az) {
                if (++st.stuck[i] >= CFG_IMU_STUCK_SAMPLES) {
                    imu_fault(i, PROTO_FAULT_IMU_BAD_DATA);
                    known = 0;
                    continue;
                }
            } else {
                st.stuck[i] = 0;
            }
            st.last[i] = a;
            g2 = (uint32_t)((int32_t)a.ax * a.ax) + (uint32_t)((int32_t)a.ay * a.ay) + (uint32_t)((int32_t)a.az * a.az);
            if (g2 < G2_MIN || g2 > G2_MAX) {
                imu_fault(i, PROTO_FAULT_IMU_BAD_DATA);
                known = 0;
                continue;
            }
            psi_update(i, a.ax, a.az);
        }
        levels[i] = psi_level(i);
        if (levels[i] == PSI_UNKNOWN) {
            known = 0;
        }
    }
    st.measured = known ? (uint32_t)seq_state_index(levels) : STATE_UNKNOWN;
}

/* ------------------------------------------------------------------ control */

static uint8_t all_settled(void)
{
    uint8_t i;
    for (i = 0; i < CFG_N_LIMBS; i++) {
        if (!psi_settled(i)) {
            return 0;
        }
    }
    return 1;
}

static void step_sequencer(void)
{
    uint8_t ev, i;
    uint16_t step;
    cfg_state_t target;
    if (!seq_running() || st.measured == STATE_UNKNOWN) {
        return;
    }
    step = seq_step();
    target = seq_target();
    /* The step counts as reached only once every limb is settled clear of its band
     * edges (psi_settled): until then the sequencer is shown a state that is not
     * the target (target ^ 1 differs from target by construction). */
    ev = seq_tick(all_settled() ? (cfg_state_t)st.measured : (cfg_state_t)(target ^ 1u));
    if (ev & SEQ_EV_REACHED) {
        send_event(PROTO_EV_STATE_REACHED, (uint8_t)(step > 255u ? 255u : step), target);
    }
    if (ev & SEQ_EV_TIMEOUT) {
        uint8_t want[CFG_N_LIMBS];
        uint16_t limb = 0;
        seq_state_levels(target, want);
        for (i = 0; i < CFG_N_LIMBS; i++) {
            if (psi_level(i) != want[i]) {
                limb = i;
                break;
            }
        }
        sma_all_off();
        st.fault = 1;
        send_event(PROTO_EV_FAULT, PROTO_FAULT_STATE_TIMEOUT, limb);
        send_event(PROTO_EV_GAIT_STOPPED, PROTO_STOP_FAULT,
                   (uint16_t)(seq_cycles() > 0xFFFFu ? 0xFFFFu : seq_cycles()));
    }
}

static void drive(void)
{
    uint16_t duty[CFG_N_ACTUATORS];
    uint8_t i, hits;
    if (seq_running() && !st.fault && !sma_estopped() && st.measured != STATE_UNKNOWN) {
        uint8_t want[CFG_N_LIMBS];
        seq_state_levels(seq_target(), want);
        ctl_demand(want, st.drive_pm, st.hold_pm, duty);
    } else {
        for (i = 0; i < CFG_N_ACTUATORS; i++) {
            duty[i] = 0;
        }
    }
    for (i = 0; i < CFG_N_ACTUATORS; i++) {
        sma_request(i, duty[i]);
    }
    hits = sma_tick();
    if (sma_take_clamped()) {
        st.clamped = 1;
    }
    for (i = 0; i < CFG_N_ACTUATORS; i++) {
        if (hits & (1u << i)) {
            /* Reported, not latched: the channel cools down and the gait goes on; a limb
             * that cannot reach its state then ends in a state timeout. */
            send_event(PROTO_EV_FAULT, PROTO_FAULT_SMA_ON_LIMIT, i);
        }
    }
}

static void watchdog(void)
{
    if (st.since_rx < 0xFFFFFFFFu) {
        st.since_rx++;
    }
    if (st.watchdog_ticks && seq_running() && st.since_rx >= st.watchdog_ticks) {
        sma_all_off();
        st.watchdog_tripped = 1;
        send_event(PROTO_EV_FAULT, PROTO_FAULT_LINK_WATCHDOG, 0);
        stop_gait(PROTO_STOP_WATCHDOG);
    }
}

static void telemetry(void)
{
    if (st.telem_hz == 0u) {
        return;
    }
    st.telem_acc = (uint16_t)(st.telem_acc + st.telem_hz);
    if (st.telem_acc >= CFG_TICK_HZ) {
        st.telem_acc = (uint16_t)(st.telem_acc - CFG_TICK_HZ);
        send_telemetry();
    }
}

/* ------------------------------------------------------------------ entry points */

void app_init(void)
{
    uint8_t i;
    memset(&st, 0, sizeof st);
    st.measured = STATE_UNKNOWN;
    st.drive_pm = CFG_DRIVE_DUTY_PM;
    st.hold_pm = CFG_HOLD_DUTY_PM;
    st.max_on_ticks = CFG_MAX_ON_TICKS;
    st.cooldown_ticks = CFG_MIN_COOLDOWN_TICKS;
    st.watchdog_ticks = CFG_LINK_WATCHDOG_TICKS;
    st.telem_hz = CFG_TELEMETRY_HZ;
    st.dir = PROTO_DIR_PLUS_X;
    sma_init();
    psi_init();
    seq_init();
    proto_rx_init(&rx);
    send_info(0);
    send_event(PROTO_EV_BOOT, 0, 0);
    for (i = 0; i < CFG_N_LIMBS; i++) {
        imu_start(i);
    }
}

void app_tick(void)
{
    st.us_acc = (uint16_t)(st.us_acc + CFG_TICK_US);
    while (st.us_acc >= 1000u) {
        st.us_acc = (uint16_t)(st.us_acc - 1000u);
        st.ms++;
    }
    poll_link();
    read_imus();
    step_sequencer();
    drive();
    watchdog();
    telemetry();
}
