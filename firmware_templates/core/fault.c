/* fault.c - see fault.h. */
#include "fault.h"

#include "hal.h"
#include "fallback.h"
#include "initzero.h"
#include "param.h"
#include "proto.h"
#include "seq.h"
#include "sma.h"
#include "tx.h"

static struct {
    uint8_t latched;
    uint8_t watchdog_tripped;
    uint32_t rx_us;    /* hal_micros() at the last valid frame */
    uint8_t rx_stale;  /* no valid frame for 2^30 µs: stays stale across the clock wrap */
} st;

static uint16_t cycles_u16(void)
{
    uint32_t cycles = seq_cycles();
    return (uint16_t)(cycles >> 16) != 0u ? 0xFFFFu : (uint16_t)cycles; /* its high half tested: no 32-bit compare */
}

void fault_init(void)
{
    INIT_ZERO(st); /* nothing latched, the watchdog not tripped, the link not stale */
    st.rx_us = hal_micros();
}

/* Stop the sequencer and report it: GAIT_STOPPED(reason, cycles). One copy for both callers. */
#if defined(__GNUC__)
__attribute__((noinline))
#endif
static void stop_gait(uint8_t reason)
{
    seq_stop();
    tx_event(PROTO_EV_GAIT_STOPPED, reason, cycles_u16());
}

void fault_stop_gait(uint8_t reason)
{
    if (seq_running()) {
        stop_gait(reason);
    }
}

/* Latch `code`; the gait (still running, or stopped by the sequencer itself: `stopped`)
 * is reported stopped; then the fallback may take over (fallback.h). */
static void raise(uint8_t code, uint16_t detail, uint8_t stopped)
{
    sma_all_off();
    st.latched = 1;
    tx_event(PROTO_EV_FAULT, code, detail);
    if (stopped || seq_running()) {
        stop_gait(PROTO_STOP_FAULT);
    }
    fallback_fault(code, detail);
}

void fault_raise(uint8_t code, uint16_t detail)
{
    raise(code, detail, 0);
}

void fault_raise_stopped(uint8_t code, uint16_t detail)
{
    raise(code, detail, 1);
}

uint8_t fault_latched(void)
{
    return st.latched;
}

void fault_clear(void)
{
    st.latched = 0;
}

void fault_heard_host(void)
{
    st.rx_us = hal_micros();
    st.rx_stale = 0;
}

/* The link watchdog is on. A build with one (CFG_LINK_WATCHDOG_MS > 0) starts it on and
 * SET_PARAM cannot turn it off (param.c: LINK_WATCHDOG_MS at least 1 ms, so at least one tick
 * of µs): then it is always on and the test folds away. */
#if CFG_LINK_WATCHDOG_MS != 0
#define WATCHDOG_ON 1
#else
#define WATCHDOG_ON (param_watchdog_us() != 0u)
#endif

void fault_watchdog_tick(void)
{
    /* safety: on real time (hal_micros, wrap-safe), not on the tick count */
    uint32_t since = hal_micros() - st.rx_us;
    if ((uint8_t)(since >> 24) >= 0x40u) { /* since ≥ 2^30: its top byte tested */
        st.rx_stale = 1;
    }
    if (st.rx_stale) {
        since = 0xFFFFFFFFUL;
    }
    if (WATCHDOG_ON && seq_running() && since >= param_watchdog_us()) {
        sma_all_off();
        st.watchdog_tripped = 1;
        tx_event(PROTO_EV_FAULT, PROTO_FAULT_LINK_WATCHDOG, 0);
        fault_stop_gait(PROTO_STOP_WATCHDOG);
    }
}

uint8_t fault_watchdog_tripped(void)
{
    return st.watchdog_tripped;
}

void fault_watchdog_rearm(void)
{
    st.watchdog_tripped = 0;
}
