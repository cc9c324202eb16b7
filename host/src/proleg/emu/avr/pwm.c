/* pwm.c - the avr-emu board's PWM read-out: each actuator channel's duty, from the registers.
 *
 * Contract. emu_set_pwm_map names the output-compare pin that drives a channel (kept
 * across every reset); emu_pwm_duty reads that pin's duty in permyriad from the current
 * core, at the moment it is called; emu_port reads a port's DDR and PORT. Nothing here
 * runs in the core's time or changes the core.
 *
 * The duty of an output-compare pin is computed from the timer registers (waveform mode,
 * TOP, OCRnx, COMnx) and, when the compare output is disconnected, from the port pin (DDR
 * and PORT), so it does not depend on simavr's pin waveform (which is wrong for Timer1
 * mode 14, fast PWM with TOP = ICR1: simavr 1.6 runs it as phase-correct).
 */
#include "harness.h"

#define EMU_API __attribute__((visibility("default")))

#define MAX_PWM 8u

/* Output-compare pins, as emu_set_pwm_map numbers them. */
enum { OC0A, OC0B, OC1A, OC1B, OC2A, OC2B, OC_COUNT };

static uint8_t pwm_map[MAX_PWM];
static uint8_t n_pwm;

static uint16_t u16(const uint8_t *d, uint16_t lo)
{
    return (uint16_t)(d[lo] | (d[lo + 1u] << 8));
}

/* Duty of an output-compare pin in permyriad, from the registers. */
static uint16_t oc_duty(uint8_t oc)
{
    static const uint8_t port_reg[OC_COUNT] = {0x2Bu, 0x2Bu, 0x25u, 0x25u, 0x25u, 0x2Bu};
    static const uint8_t pin_bit[OC_COUNT] = {6u, 5u, 1u, 2u, 3u, 3u};
    const uint8_t *d = emu_core()->data;
    uint8_t port = port_reg[oc], bit = pin_bit[oc];
    uint8_t com, wgm, cs, fast;
    uint32_t top, ocr;
    uint64_t duty;
    if (!(d[port - 1u] & (1u << bit))) {
        return 0; /* pin is an input: the gate pull-down holds the MOSFET off */
    }
    switch (oc) {
    case OC1A:
    case OC1B:
        com = (uint8_t)((d[0x80] >> (oc == OC1A ? 6 : 4)) & 3u);
        wgm = (uint8_t)((d[0x80] & 3u) | ((d[0x81] >> 1) & 0x0Cu));
        cs = d[0x81] & 7u;
        ocr = u16(d, oc == OC1A ? 0x88u : 0x8Au);
        switch (wgm) {
        case 1: top = 0xFFu; fast = 0; break;
        case 2: top = 0x1FFu; fast = 0; break;
        case 3: top = 0x3FFu; fast = 0; break;
        case 5: top = 0xFFu; fast = 1; break;
        case 6: top = 0x1FFu; fast = 1; break;
        case 7: top = 0x3FFu; fast = 1; break;
        case 8: case 10: top = u16(d, 0x86u); fast = 0; break;
        case 9: case 11: top = u16(d, 0x88u); fast = 0; break;
        case 14: top = u16(d, 0x86u); fast = 1; break;
        case 15: top = u16(d, 0x88u); fast = 1; break;
        default: com = 0; top = 0; fast = 0; break; /* normal / CTC: no PWM */
        }
        if ((wgm == 9 || wgm == 11 || wgm == 15) && oc == OC1A) {
            com = 0; /* OCR1A is TOP: OC1A only toggles (not a duty) */
        }
        break;
    default: {
        uint8_t a = (oc <= OC0B) ? 0x44u : 0xB0u; /* TCCRnA; TCCRnB = +1, OCRnA = +3, OCRnB = +4 */
        uint8_t is_a = (oc == OC0A || oc == OC2A);
        com = (uint8_t)((d[a] >> (is_a ? 6 : 4)) & 3u);
        wgm = (uint8_t)((d[a] & 3u) | ((d[a + 1u] >> 1) & 4u));
        cs = d[a + 1u] & 7u;
        ocr = d[a + (is_a ? 3u : 4u)];
        switch (wgm) {
        case 1: top = 0xFFu; fast = 0; break;
        case 3: top = 0xFFu; fast = 1; break;
        case 5: top = d[a + 3u]; fast = 0; break;
        case 7: top = d[a + 3u]; fast = 1; break;
        default: com = 0; top = 0; fast = 0; break;
        }
        if ((wgm == 5 || wgm == 7) && is_a) {
            com = 0;
        }
        break;
    }
    }
    if (com < 2u || cs == 0u) {
        /* Compare output disconnected (or toggle-only, or timer stopped): the port bit. */
        return (d[port] & (1u << bit)) ? 10000u : 0u;
    }
    if (fast) {
        duty = ocr >= top ? 10000u : ((uint64_t)(ocr + 1u) * 10000u + (top + 1u) / 2u) / (top + 1u);
    } else {
        duty = top == 0u ? 0u : (ocr >= top ? 10000u : ((uint64_t)ocr * 10000u + top / 2u) / top);
    }
    return (uint16_t)(com == 3u ? 10000u - duty : duty);
}

/* -- the ABI ------------------------------------------------------------------------ */

EMU_API int emu_set_pwm_map(uint8_t channel, uint8_t oc)
{
    if (channel >= MAX_PWM || oc >= OC_COUNT) {
        return -1;
    }
    pwm_map[channel] = oc;
    if (channel >= n_pwm) {
        n_pwm = (uint8_t)(channel + 1u);
    }
    return 0;
}

EMU_API uint16_t emu_pwm_duty(uint8_t channel)
{
    return channel < n_pwm ? oc_duty(pwm_map[channel]) : 0u;
}

/* (DDRx << 8) | PORTx of port 'B', 'C' or 'D'. */
EMU_API uint16_t emu_port(char name)
{
    const uint8_t *d = emu_core()->data;
    uint8_t base = name == 'B' ? 0x24u : name == 'C' ? 0x27u : 0x2Au;
    return (uint16_t)((d[base] << 8) | d[base + 1u]);
}
