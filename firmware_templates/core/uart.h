/* uart.h - the host link's byte queues between the UART interrupts and the core.
 *
 * Contract. Two rings (ring.h) of CFG_UART_RX_BYTES and CFG_UART_TX_BYTES (the board
 * file's [uart] rx_buffer and tx_buffer). The core side: uart_write() queues what fits
 * and returns how many bytes it took, never waiting (the caller counts the rest as
 * dropped: telemetry never stalls the control loop), then asks the HAL to start
 * sending (hal_uart_tx_start); uart_read_byte() returns the next received byte or -1.
 * The HAL side, from its interrupt handlers: uart_isr_rx() for every received byte (a
 * full ring drops it; the protocol's CRC and NACKs handle the loss) and uart_isr_tx()
 * for the next byte to send, -1 when there is none (then the HAL stops the transmit
 * interrupt until the next hal_uart_tx_start). uart_init() empties both rings.
 */
#ifndef PROLEG_UART_H
#define PROLEG_UART_H

#include <stdint.h>

void uart_init(void);
uint16_t uart_write(const uint8_t *data, uint16_t n);
int uart_read_byte(void);

/* 0, or -1 when the ring was full and the byte was dropped. */
int8_t uart_isr_rx(uint8_t b);
int uart_isr_tx(void);

#endif /* PROLEG_UART_H */
