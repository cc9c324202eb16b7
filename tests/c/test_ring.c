/* test_ring.c - drives core/ring.h from stdin for tests/test_firmware_ring.py.
 *
 * Built with -DCFG_UART_RX_BYTES=<size> (and a tiny robot_config.h that only includes
 * nothing else). Input: one op per line, "p <byte>" (put) or "g" (get). Output: one line
 * per op, the put's result (0 / -1) or the byte got (-1 when empty). */
#include <stdio.h>

#include "ring.h"

static volatile uint8_t mem[CFG_UART_RX_BYTES];
static ring_t r;

int main(void)
{
    char op;
    int b;
    ring_clear(&r);
    while (scanf(" %c", &op) == 1) {
        if (op == 'p') {
            if (scanf("%d", &b) != 1) {
                return 2;
            }
            printf("%d\n", ring_put(&r, mem, (ring_index_t)(CFG_UART_RX_BYTES - 1u), (uint8_t)b));
        } else {
            printf("%d\n", ring_get(&r, mem, (ring_index_t)(CFG_UART_RX_BYTES - 1u)));
        }
    }
    return 0;
}
