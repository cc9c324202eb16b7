/* tx.h - messages to the host: encode, queue on the UART, count what was lost.
 *
 * Contract. tx_msg is the one message buffer of the application: the command being
 * handled is decoded into it, and each reply and event is then built in it, so a
 * handler reads every field it needs before it sends anything. tx_send() encodes
 * tx_msg and queues the whole frame with uart_write (uart.h), never waiting: a frame that
 * does not fit is dropped and counted (tx_dropped); when only part of it went out, the
 * next frame starts with a delimiter so the host resynchronises. On a board whose host
 * link is CAN (CFG_LINK_CAN) tx_send() hands the message to canlink.h instead: all of its
 * frames are queued or it is dropped and counted. The helpers build
 * EVENT, ACK and NACK (NACKs are counted) stamped with the firmware clock (app.h).
 */
#ifndef PROLEG_TX_H
#define PROLEG_TX_H

#include <stdint.h>

#include "proto.h"

typedef struct {
    uint32_t nacks, tx_frames, tx_dropped;
} tx_counts_t;

extern proto_msg_t tx_msg;

void tx_init(void);
void tx_send(void);
/* The same for a message built elsewhere (the telemetry frame, telemetry.h). */
void tx_send_msg(const proto_msg_t *m);
void tx_event(uint8_t kind, uint8_t code, uint16_t detail);
void tx_ack(uint8_t token, uint8_t cmd);
void tx_nack(uint8_t token, uint8_t cmd, uint8_t error, uint16_t detail);

/* NACKs sent, frames sent, frames dropped since tx_init or tx_clear_counts. */
const tx_counts_t *tx_counts(void);
void tx_clear_counts(void);

#endif /* PROLEG_TX_H */
