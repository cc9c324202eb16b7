/* tx.c - see tx.h. */
#include "tx.h"

#include <string.h>

#include "app.h"
#include "count.h"
#include "initzero.h"
#include "robot_config.h"
#include "uart.h"
#if CFG_LINK_CAN
#include "canlink.h"
#endif

proto_msg_t tx_msg;

static tx_counts_t count;
#if !CFG_LINK_CAN
static uint8_t txbuf[PROTO_MAX_ENCODED];
static uint8_t pending_delim; /* a frame went out half: start the next with a delimiter */
#endif

void tx_init(void)
{
    INIT_ZERO(count);
#if CFG_LINK_CAN
    canlink_init(); /* the host link is the CAN bus (board file [link] transport = "can") */
#else
    INIT_ZERO(pending_delim);
#endif
}

void tx_send(void)
{
    tx_send_msg(&tx_msg);
}

#if CFG_LINK_CAN
void tx_send_msg(const proto_msg_t *m)
{
    if (canlink_send(m)) { /* every frame of it queued, or none */
        count_up(&count.tx_frames);
    } else {
        count_up(&count.tx_dropped);
    }
}
#else
void tx_send_msg(const proto_msg_t *m)
{
    size_t n = proto_encode(m, txbuf, sizeof txbuf);
    uint16_t w;
    if (n == 0u) {
        count_up(&count.tx_dropped);
        return;
    }
    if (pending_delim) {
        uint8_t zero = 0;
        if (uart_write(&zero, 1) != 1u) {
            count_up(&count.tx_dropped);
            return;
        }
        pending_delim = 0;
    }
    w = uart_write(txbuf, (uint16_t)n);
    if (w == n) {
        count_up(&count.tx_frames);
    } else {
        count_up(&count.tx_dropped);
        pending_delim = (uint8_t)(w > 0u);
    }
}
#endif

void tx_event(uint8_t kind, uint8_t code, uint16_t detail)
{
    tx_msg.id = PROTO_ID_EVENT;
    tx_msg.u.event.time_ms = app_time_ms();
    tx_msg.u.event.kind = kind;
    tx_msg.u.event.code = code;
    tx_msg.u.event.detail = detail;
    tx_send();
}

void tx_ack(uint8_t token, uint8_t cmd)
{
    tx_msg.id = PROTO_ID_ACK;
    tx_msg.u.ack.token = token;
    tx_msg.u.ack.cmd = cmd;
    tx_send();
}

void tx_nack(uint8_t token, uint8_t cmd, uint8_t error, uint16_t detail)
{
    count_up(&count.nacks);
    tx_msg.id = PROTO_ID_NACK;
    tx_msg.u.nack.token = token;
    tx_msg.u.nack.cmd = cmd;
    tx_msg.u.nack.error = error;
    tx_msg.u.nack.detail = detail;
    tx_send();
}

const tx_counts_t *tx_counts(void)
{
    return &count;
}

void tx_clear_counts(void)
{
    memset(&count, 0, sizeof count);
}
