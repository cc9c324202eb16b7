/* uart.c - see uart.h. */
#include "uart.h"

#include "hal.h"
#include "ring.h"

#if (CFG_UART_RX_BYTES & (CFG_UART_RX_BYTES - 1u)) || (CFG_UART_TX_BYTES & (CFG_UART_TX_BYTES - 1u))
#error "the UART buffers must be powers of two"
#endif

#define RX_MASK ((ring_index_t)(CFG_UART_RX_BYTES - 1u))
#define TX_MASK ((ring_index_t)(CFG_UART_TX_BYTES - 1u))

static volatile uint8_t rx_mem[CFG_UART_RX_BYTES], tx_mem[CFG_UART_TX_BYTES];
static ring_t rx, tx;

void uart_init(void)
{
    ring_clear(&rx);
    ring_clear(&tx);
}

uint16_t uart_write(const uint8_t *data, uint16_t n)
{
    uint16_t i;
    for (i = 0; i < n; i++) {
        if (ring_put(&tx, tx_mem, TX_MASK, data[i]) != 0) {
            break;
        }
    }
    if (i) {
        hal_uart_tx_start();
    }
    return i;
}

int uart_read_byte(void)
{
    return ring_get(&rx, rx_mem, RX_MASK);
}

int8_t uart_isr_rx(uint8_t b)
{
    return ring_put(&rx, rx_mem, RX_MASK, b);
}

int uart_isr_tx(void)
{
    return ring_get(&tx, tx_mem, TX_MASK);
}
