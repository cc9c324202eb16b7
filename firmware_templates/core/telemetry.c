/* telemetry.c - see telemetry.h. */
#include "telemetry.h"

#include "drive.h"
#include "hal.h"
#include "fault.h"
#include "imucheck.h"
#include "initzero.h"
#include "proto.h"
#include "psi.h"
#include "robot_config.h"
#include "seq.h"
#include "sma.h"
#include "tx.h"
#include "app.h"

/* Wire bytes of one TELEMETRY frame: 15 fixed + 2 counts + 2/limb + 2/actuator + CRC 2
 * + COBS overhead 1 + delimiter 1 (rounded up to 24 fixed). */
#define TELEMETRY_WIRE_BYTES (24UL + 2UL * CFG_N_LIMBS + 2UL * CFG_N_ACTUATORS)
#define TELEMETRY_LINK_HZ (CFG_UART_BAUD / 10UL / TELEMETRY_WIRE_BYTES / 2UL)
#define TELEMETRY_MAX_HZ (TELEMETRY_LINK_HZ < CFG_TICK_HZ ? TELEMETRY_LINK_HZ : CFG_TICK_HZ)

static struct {
    uint16_t hz, acc, seq;
    uint8_t clamped;
    uint8_t pending;  /* `frame` is taken, not yet sent */
    uint16_t cost_us; /* the longest encode-and-queue seen so far (starts at a quarter tick) */
    proto_msg_t frame;
} st;

void telemetry_init(void)
{
    INIT_ZERO(st); /* no frame taken or pending, sequence 0 */
    st.hz = CFG_TELEMETRY_HZ;
    st.cost_us = (uint16_t)(CFG_TICK_US / 4u); /* then learnt */
}

uint8_t telemetry_set_rate(uint16_t hz)
{
    if (hz > TELEMETRY_MAX_HZ) {
        return 1;
    }
    st.hz = hz;
    st.acc = 0;
    return 0;
}

uint16_t telemetry_rate(void)
{
    return st.hz;
}

void telemetry_note_clamped(void)
{
    st.clamped = 1;
}

uint16_t telemetry_flags(void)
{
    uint16_t f = 0;
    uint8_t i;
    if (seq_running()) {
        f |= PROTO_FLAG_RUNNING;
    }
    if (seq_holding()) {
        f |= PROTO_FLAG_HOLDING;
    }
    if (fault_latched()) {
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
    if (imucheck_bad()) {
        f |= PROTO_FLAG_IMU_FAULT;
    }
    if (fault_watchdog_tripped()) {
        f |= PROTO_FLAG_LINK_WATCHDOG;
    }
    if (seq_gait_count(SEQ_DIR_LOADED)) {
        f |= PROTO_FLAG_USER_GAIT;
    }
    if (imucheck_measured() == IMUCHECK_UNKNOWN) {
        f |= PROTO_FLAG_STATE_UNKNOWN;
    }
    return f;
}

/* Take the frame's values now (in the tick); telemetry_idle() encodes and queues it. */
static void take_telemetry(void)
{
    uint8_t i;
    proto_msg_t *m = &st.frame;
    m->id = PROTO_ID_TELEMETRY;
    m->u.telemetry.seq = st.seq++;
    m->u.telemetry.time_ms = app_time_ms();
    m->u.telemetry.measured = (uint16_t)imucheck_measured();
    m->u.telemetry.target = (uint16_t)seq_target();
    m->u.telemetry.gait = drive_gait();
    m->u.telemetry.direction = drive_dir();
    m->u.telemetry.step = seq_step_byte();
    m->u.telemetry.flags = telemetry_flags();
    m->u.telemetry.psi_count = CFG_N_LIMBS;
    for (i = 0; i < CFG_N_LIMBS; i++) {
        m->u.telemetry.psi[i] = psi_last_centideg(i);
    }
    m->u.telemetry.duty_count = CFG_N_ACTUATORS;
    for (i = 0; i < CFG_N_ACTUATORS; i++) {
        m->u.telemetry.duty[i] = sma_duty(i);
    }
    st.clamped = 0;
    st.pending = 1;
}

void telemetry_tick(void)
{
    if (st.hz == 0u) {
        return;
    }
    st.acc = (uint16_t)(st.acc + st.hz);
    if (st.acc >= CFG_TICK_HZ) {
        st.acc = (uint16_t)(st.acc - CFG_TICK_HZ);
        if (st.pending) {
            tx_send_msg(&st.frame); /* no idle time was long enough: send it in the tick */
        }
        take_telemetry();
    }
}

void telemetry_idle(uint32_t until_next_tick_us)
{
    uint32_t t0, dt;
    uint16_t d;
    if (!st.pending || until_next_tick_us <= st.cost_us) {
        return;
    }
    t0 = hal_micros();
    tx_send_msg(&st.frame);
    st.pending = 0;
    dt = hal_micros() - t0;
    d = (uint16_t)(dt >> 16) != 0u ? 0xFFFFu : (uint16_t)dt; /* at most 0xFFFF: its high half tested */
    if (d > st.cost_us) {
        st.cost_us = d;
    }
}
