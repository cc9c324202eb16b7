/* cmd.h - commands from the host: decode the link's bytes, answer each command.
 *
 * Contract. cmd_poll() runs first in every tick: it takes at most 2 frames' worth of
 * bytes from the UART (uart_read_byte), decodes them (proto.h) and answers every
 * complete command before it returns, each with the reply the protocol definition names
 * (ACK, NACK with an error code, INFO, STATS); a CRC-valid frame the decoder refuses is
 * NACKed. ESTOP turns every MOSFET off before its ACK is sent. A valid frame restarts
 * the link watchdog (fault.h). cmd_send_info() is also the unsolicited INFO at boot.
 */
#ifndef PROLEG_CMD_H
#define PROLEG_CMD_H

#include <stdint.h>

/* kept: the reset kept the coils' budget (sma_init), passed on to level_init. */
void cmd_init(uint8_t kept);
void cmd_poll(void);
void cmd_send_info(uint8_t token);

#endif /* PROLEG_CMD_H */
