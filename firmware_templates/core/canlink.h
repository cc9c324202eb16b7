/* canlink.h - the host link on a CAN bus: protocol messages as classic CAN frames.
 *
 * Contract. In images whose board file says [link] transport = "can" (CFG_LINK_CAN) the
 * protocol travels in 8-byte frames with 11-bit identifiers laid out exactly as
 * proleg.protocol.can describes (and `proleg dbc` writes into a DBC): identifier =
 * CFG_CAN_BASE_ID + slot * 16 + CFG_CAN_NODE; slot 0 CMD (host -> robot) and slot 1 REPLY
 * carry a message's unframed bytes `msg_id | payload | crc16` in segments (byte 0 = index
 * | (data bytes - 1) << 4 | 0x80 on the last, then 7 data bytes, zero-padded); TELEMETRY
 * goes in its fixed frames (slots 2 A, 3 B, 4-5 psi, 6-7 duty; a psi/duty frame only when
 * it carries a used element) and EVENT in its own fixed frame (slot 8).
 *
 * The core side: canlink_send() queues every frame of one message or none (1 / 0: the
 * caller counts the drop), never waiting, then asks the HAL to send (hal_can_tx_start).
 * The queue holds CFG_CAN_TX_FRAMES frames. The HAL side, from its interrupt handlers:
 * canlink_isr_tx() hands it the next frame (-1: none), canlink_isr_rx() takes a received
 * frame. A complete CMD message is handed to the command parser as wire bytes (0x00, its
 * COBS frame, 0x00) through the receive ring (uart_isr_rx), so the parser's CRC check,
 * counters and NACKs work as on the UART; a message lost in assembly (a segment missing,
 * out of order, or too long) is handed over as one broken frame, counted as a framing
 * error. canlink_init() empties the queue and starts the controller (hal_can_init).
 */
#ifndef PROLEG_CANLINK_H
#define PROLEG_CANLINK_H

#include <stdint.h>

#include "proto.h"

typedef struct {
    uint16_t id; /* 11-bit standard identifier */
    uint8_t dlc;
    uint8_t data[8];
} can_frame_t;

/* Slots of the identifier scheme (proleg.protocol.can). */
#define CANLINK_SLOT_CMD 0u
#define CANLINK_SLOT_REPLY 1u
#define CANLINK_SLOT_EVENT 8u
#define CANLINK_ID(slot) ((uint16_t)(CFG_CAN_BASE_ID + ((uint16_t)(slot) << 4) + CFG_CAN_NODE))

void canlink_init(void);
uint8_t canlink_send(const proto_msg_t *m);

void canlink_isr_rx(uint16_t id, const uint8_t *data, uint8_t dlc);
int8_t canlink_isr_tx(can_frame_t *out);

/* The HAL's part (hal/<family>/can*.c, in CAN images only; hal.h is the rest of the port).
 * hal_can_init: the CAN controller at CFG_CAN_BTR on the board's pins, receiving only this
 * node's command identifier (CANLINK_ID(CANLINK_SLOT_CMD)) into canlink_isr_rx from its
 * receive interrupt; called by canlink_init, never waits on the bus (a bus that never goes
 * idle leaves the controller waiting to join, not the core). hal_can_tx_start: frames are
 * waiting: load the free transmit mailboxes from canlink_isr_tx, in order (the segments of
 * a message share an identifier and must not overtake each other); the transmit-complete
 * interrupt takes the rest. Called from the main loop; returns at once. */
void hal_can_init(void);
void hal_can_tx_start(void);

#endif /* PROLEG_CANLINK_H */
