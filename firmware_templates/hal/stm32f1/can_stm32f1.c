/* can_stm32f1.c - the host link on the STM32F103's bxCAN (images with [link] transport = "can").
 *
 * RM0008 (Rev 21) chapter 24 is the reference; section numbers below are its. The
 * controller leaves reset asleep (§24.4, MCR = 0x00010002); hal_can_init asks for
 * initialisation mode (INRQ, waiting a bounded time for INAK, §24.4.1), sets the bit
 * timing the build computed from the board file's [can] clock_hz and bitrate (CFG_CAN_BTR,
 * §24.7.7), transmit priority by request order (TXFP: a message's segments share one
 * identifier and must leave in order, §24.7.1), automatic bus-off recovery (ABOM), and one
 * 32-bit mask filter (bank 0 -> FIFO 0) that passes exactly this node's command identifier
 * as a standard data frame (§24.7.4), then leaves initialisation without waiting: the
 * controller joins the bus by itself after 11 recessive bits (§24.4.2).
 * Transmit: hal_can_tx_start loads free mailboxes (TSR.CODE names the next free one) with
 * the NVIC's transmit interrupt masked; the interrupt (TMEIE: on a request completed,
 * RQCPx, §24.8) clears RQCPx and loads the next frames. Receive: FMPIE0's interrupt reads
 * one message from FIFO 0, releases it (RFOM0) and hands it to canlink_isr_rx; with
 * another message pending the interrupt stays asserted and comes again. A FIFO overrun
 * (FOVR0) loses a segment: its message reaches the parser broken and is counted there.
 * Pins: CAN_RX input with pull-up, CAN_TX alternate push-pull (§9.1.11, Table 24), on
 * PA11/PA12 or, with AFIO_MAPR CAN_REMAP = 10, PB8/PB9 (§9.3.3); CFG_CAN_REMAP.
 * If the chip is not running on the PLL (no crystal: hal_stm32f1.c stays on HSI), PCLK1 is
 * not the clock CFG_CAN_BTR was computed for: the controller is left off the bus rather
 * than disturbing it at a wrong bit rate.
 */
#include <stdint.h>

#include "canlink.h"
#include "hal.h"
#include "robot_config.h"
#include "stm32f1_regs.h"

#define CAN_BASE 0x40006400u
#define CAN_MCR REG32(CAN_BASE + 0x000u)
#define CAN_MSR REG32(CAN_BASE + 0x004u)
#define CAN_TSR REG32(CAN_BASE + 0x008u)
#define CAN_RF0R REG32(CAN_BASE + 0x00Cu)
#define CAN_IER REG32(CAN_BASE + 0x014u)
#define CAN_BTR REG32(CAN_BASE + 0x01Cu)
#define CAN_TIR(m) REG32(CAN_BASE + 0x180u + 0x10u * (m))
#define CAN_TDTR(m) REG32(CAN_BASE + 0x184u + 0x10u * (m))
#define CAN_TDLR(m) REG32(CAN_BASE + 0x188u + 0x10u * (m))
#define CAN_TDHR(m) REG32(CAN_BASE + 0x18Cu + 0x10u * (m))
#define CAN_RI0R REG32(CAN_BASE + 0x1B0u)
#define CAN_RDT0R REG32(CAN_BASE + 0x1B4u)
#define CAN_RDL0R REG32(CAN_BASE + 0x1B8u)
#define CAN_RDH0R REG32(CAN_BASE + 0x1BCu)
#define CAN_FMR REG32(CAN_BASE + 0x200u)
#define CAN_FM1R REG32(CAN_BASE + 0x204u)
#define CAN_FS1R REG32(CAN_BASE + 0x20Cu)
#define CAN_FFA1R REG32(CAN_BASE + 0x214u)
#define CAN_FA1R REG32(CAN_BASE + 0x21Cu)
#define CAN_F0R1 REG32(CAN_BASE + 0x240u)
#define CAN_F0R2 REG32(CAN_BASE + 0x244u)

#define CAN_MCR_INRQ (1u << 0)
#define CAN_MCR_TXFP (1u << 2)
#define CAN_MCR_ABOM (1u << 6)
#define CAN_MCR_DBF (1u << 16)
#define CAN_MSR_INAK (1u << 0)
#define CAN_TSR_RQCP_ALL ((1u << 0) | (1u << 8) | (1u << 16))
#define CAN_TSR_TME_ANY (7u << 26)
#define CAN_RF0R_FMP0 3u
#define CAN_RF0R_FOVR0 (1u << 4)
#define CAN_RF0R_RFOM0 (1u << 5)
#define CAN_IER_TMEIE (1u << 0)
#define CAN_IER_FMPIE0 (1u << 1)
#define CAN_TIR_TXRQ (1u << 0)
#define CAN_RIR_RTR (1u << 1)
#define CAN_RIR_IDE (1u << 2)
#define CAN_FMR_FINIT (1u << 0)

#define AFIO_MAPR REG32(0x40010004u)
#define RCC_APB1_CAN (1u << 25)
#define CAN_TX_IRQN 19u /* USB_HP_CAN_TX */
#define CAN_RX0_IRQN 20u /* USB_LP_CAN_RX0 */
#define NVIC_ICER(n) REG32(0xE000E180u + 4u * (n))
#define INAK_SPINS 20000u /* INAK follows INRQ within a frame time when the bus is busy */

void USB_HP_CAN_TX_IRQHandler(void);
void USB_LP_CAN_RX0_IRQHandler(void);

static void pin(uint32_t base, uint8_t n, uint32_t mode)
{
    volatile uint32_t *cr = n < 8u ? &GPIO_CRL(base) : &GPIO_CRH(base);
    uint32_t shift = 4u * (n & 7u);
    *cr = (*cr & ~(0xFu << shift)) | (mode << shift);
}

static uint32_t le32(const uint8_t *d)
{
    return (uint32_t)d[0] | (uint32_t)d[1] << 8 | (uint32_t)d[2] << 16 | (uint32_t)d[3] << 24;
}

static void unle32(uint8_t *d, uint32_t v)
{
    d[0] = (uint8_t)v;
    d[1] = (uint8_t)(v >> 8);
    d[2] = (uint8_t)(v >> 16);
    d[3] = (uint8_t)(v >> 24);
}

/* Load free mailboxes, in order, while frames wait (caller: interrupt, or transmit IRQ masked). */
static void fill(void)
{
    can_frame_t f;
    uint32_t tsr, mb;
    while ((tsr = CAN_TSR) & CAN_TSR_TME_ANY) {
        if (canlink_isr_tx(&f) < 0) {
            return;
        }
        mb = (tsr >> 24) & 3u; /* CODE: the next free mailbox */
        CAN_TDTR(mb) = f.dlc;
        CAN_TDLR(mb) = le32(f.data);
        CAN_TDHR(mb) = le32(f.data + 4);
        CAN_TIR(mb) = (uint32_t)f.id << 21 | CAN_TIR_TXRQ;
    }
}

void hal_can_init(void)
{
    uint32_t spins = INAK_SPINS;
    if ((RCC_CFGR & (3u << 2)) != (2u << 2)) {
        return; /* not on the PLL: PCLK1 is not what CFG_CAN_BTR assumes */
    }
    RCC_APB2ENR |= RCC_APB2_AFIO | RCC_APB2_IOPA | RCC_APB2_IOPB;
    RCC_APB1ENR |= RCC_APB1_CAN;
    AFIO_MAPR = (AFIO_MAPR & ~(3u << 13)) | ((uint32_t)CFG_CAN_REMAP << 13);
#if CFG_CAN_REMAP == 2u
    pin(GPIOB_BASE, 8, GPIO_IN_PULL);
    GPIO_BSRR(GPIOB_BASE) = 1u << 8;
    pin(GPIOB_BASE, 9, GPIO_AF_PP_50MHZ);
#else
    pin(GPIOA_BASE, 11, GPIO_IN_PULL);
    GPIO_BSRR(GPIOA_BASE) = 1u << 11;
    pin(GPIOA_BASE, 12, GPIO_AF_PP_50MHZ);
#endif
    CAN_MCR = CAN_MCR_INRQ | CAN_MCR_DBF; /* out of sleep, into initialisation */
    while (!(CAN_MSR & CAN_MSR_INAK)) {
        if (--spins == 0u) {
            return; /* the controller did not answer: stay off the bus */
        }
    }
    CAN_MCR = CAN_MCR_INRQ | CAN_MCR_DBF | CAN_MCR_TXFP | CAN_MCR_ABOM;
    CAN_BTR = CFG_CAN_BTR;
    CAN_FMR |= CAN_FMR_FINIT;
    CAN_FA1R &= ~1u;
    CAN_FM1R &= ~1u;  /* identifier mask mode */
    CAN_FS1R |= 1u;   /* one 32-bit filter */
    CAN_FFA1R &= ~1u; /* to FIFO 0 */
    CAN_F0R1 = (uint32_t)CANLINK_ID(CANLINK_SLOT_CMD) << 21;      /* IDE = 0, RTR = 0 */
    CAN_F0R2 = (0x7FFu << 21) | CAN_RIR_IDE | CAN_RIR_RTR;         /* all of them must match */
    CAN_FA1R |= 1u;
    CAN_FMR &= ~CAN_FMR_FINIT;
    CAN_IER = CAN_IER_TMEIE | CAN_IER_FMPIE0;
    NVIC_ISER(0) = (1u << CAN_TX_IRQN) | (1u << CAN_RX0_IRQN);
    CAN_MCR = CAN_MCR_DBF | CAN_MCR_TXFP | CAN_MCR_ABOM; /* leave initialisation: joins when the bus idles */
}

void hal_can_tx_start(void)
{
    NVIC_ICER(0) = 1u << CAN_TX_IRQN; /* the interrupt loads mailboxes too: not both at once */
    fill();
    NVIC_ISER(0) = 1u << CAN_TX_IRQN;
}

void USB_HP_CAN_TX_IRQHandler(void)
{
    CAN_TSR = CAN_TSR_RQCP_ALL; /* write 1 to clear (also clears TXOK, ALST, TERR) */
    fill();
}

void USB_LP_CAN_RX0_IRQHandler(void)
{
    uint8_t data[8];
    uint32_t rir, dlc;
    if (CAN_RF0R & CAN_RF0R_FMP0) {
        rir = CAN_RI0R;
        dlc = CAN_RDT0R & 0xFu;
        unle32(data, CAN_RDL0R);
        unle32(data + 4, CAN_RDH0R);
        CAN_RF0R = CAN_RF0R_RFOM0;
        if (!(rir & (CAN_RIR_IDE | CAN_RIR_RTR))) {
            canlink_isr_rx((uint16_t)(rir >> 21), data, (uint8_t)(dlc > 8u ? 8u : dlc));
        }
    }
    if (CAN_RF0R & CAN_RF0R_FOVR0) {
        CAN_RF0R = CAN_RF0R_FOVR0;
    }
}
