/*
 * hal_psoc5lp.c - the core's HAL on PSoC Creator components (CY8CKIT-059, CY8C5888LTI-LP097).
 *
 * Encoder:   QuadDec, 32-bit counter, 4x resolution: a 256-line encoder gives the
 *            rig's 1024 counts per base revolution.
 * Accel:     ADC_DelSig "ADC", continuous conversion; the tick reads the latest result.
 * Motor:     two DVDACs (12-bit, 0-4.080 V range: SetValue takes 0..0xFF0, 1 mV per
 *            code) buffered by opamp followers drive the amplifier's differential input:
 *            V = V(P) - V(N), each side moving half of it around 2.048 V, so +-255 counts
 *            = +-2.5 V and 0 counts = 0 V exactly (within half a DVDAC code, 0.5 mV).
 * Enable:    pin AMP_EN, inactive level at reset (set in the pin's initial drive state).
 * Link:      USBUART (USB CDC on the kit's PSoC USB connector, /dev/ttyACM0 on Linux).
 */
#include "hal_psoc5lp.h"

#include "project.h"
#include "sflr_hal.h"

#include "hal_wiring.h"

/* DVDAC codes: a 12-bit DVDAC dithers the 8-bit VDAC (16 mV per step in its 0-4.080 V
 * range) over 16 sub-steps: 1 mV per code, valid codes 0..0xFF0 (4080 = 4.080 V), not
 * 4096 codes over 4.080 V. One DAC count is 2.5 V / 255 = 2500/255 = 9.8039 codes
 * differential, split between the two sides. */
#define DAC_MID 2048            /* 2.048 V on each side at 0 V differential */
#define DAC_MV_FULL_SCALE 2500  /* differential codes (mV) for DAC_FULL_SCALE */
#define DAC_FULL_SCALE 255      /* DAC counts for 2.5 V */

/* ------------------------------------------------------------ HAL functions */

int32_t hal_encoder_read(void) { return (int32_t)ENCODER_SIGN * (int32_t)QuadDec_GetCounter(); }

void hal_encoder_reset(void) { QuadDec_SetCounter(0); }

int16_t hal_accel_read(void)
{
    /* Latest continuous-mode result: never waits inside the tick interrupt. Flipping a
     * saturated -32768 gives +32767, not a wrap back to -32768. */
    int32_t a = (int32_t)ACCEL_SIGN * (int32_t)ADC_GetResult16();
    return a > INT16_MAX ? (int16_t)INT16_MAX : (int16_t)a;
}

void hal_dac_write(int16_t v)
{
    int32_t c = v > DAC_FULL_SCALE ? DAC_FULL_SCALE : (v < -DAC_FULL_SCALE ? -DAC_FULL_SCALE : v);
    /* nearest code, integer only (interrupt context); 255 is odd, so c*2500/255 is never
     * exactly half-way between two codes */
    int32_t m = c * DAC_MV_FULL_SCALE;
    int32_t d = m >= 0 ? (m + DAC_FULL_SCALE / 2) / DAC_FULL_SCALE
                       : -((-m + DAC_FULL_SCALE / 2) / DAC_FULL_SCALE); /* differential codes */
    int32_t p = d / 2;                                               /* P takes half, N the rest: */
    DAC_P_SetValue((uint16)(DAC_MID + p));                           /* P - N == d exactly */
    DAC_N_SetValue((uint16)(DAC_MID - (d - p)));
}

void hal_amp_enable(bool on) { AMP_EN_Write(on ? AMP_EN_ACTIVE : (uint8)(AMP_EN_ACTIVE ^ 1u)); }

/* Transmit queue: filled from the tick interrupt (and from received-frame handling,
 * which runs with interrupts masked), drained to USB by the main loop. */
#define TXQ_SIZE 512u /* power of two; > 2 ms of SAMPLEs plus an INFO and a STOPPED */
static uint8 txq[TXQ_SIZE];
static volatile uint16 txq_head, txq_tail; /* head: write index, tail: read index */

void hal_uart_write(const uint8_t *data, size_t n)
{
    uint8 s = CyEnterCriticalSection();
    uint16 used = (uint16)((txq_head - txq_tail) & (TXQ_SIZE - 1u));
    /* whole frames only: drop rather than block (the station sees the gap in seq) */
    if (n <= (size_t)(TXQ_SIZE - 1u - used)) {
        for (size_t i = 0; i < n; i++) {
            txq[txq_head] = data[i];
            txq_head = (uint16)((txq_head + 1u) & (TXQ_SIZE - 1u));
        }
    }
    CyExitCriticalSection(s);
}

/* ------------------------------------------------------------ init and main loop */

void hal_psoc5lp_init(void)
{
    /* Enable inactive first (the pin's reset state already is), then the DAC at 0 V. */
    hal_amp_enable(false);
    DAC_P_Start();
    DAC_N_Start();
    hal_dac_write(0);
    BUF_P_Start();
    BUF_N_Start();
    QuadDec_Start();
    QuadDec_SetCounter(0);
    ADC_Start();
    ADC_StartConvert();
    Clock_tick_Start();
}

/* Hardware watchdog: fed by the main loop, but only when the tick interrupt has run
 * since the last feed (tick_count is written by the interrupt only; a 32-bit aligned
 * load on the Cortex-M3 is atomic). */
static volatile uint32 tick_count;
static uint32 tick_count_fed;

void hal_psoc5lp_tick(sflr_dev_t *dev)
{
    sflr_tick(dev);
    tick_count++;
}

void hal_psoc5lp_watchdog_start(void)
{
#ifndef SFLR_NO_HW_WATCHDOG
    CyILO_Start1K(); /* the WDT counts the 1 kHz ILO */
    CyWdtStart(CYWDT_16_TICKS, CYWDT_LPMODE_NOCHANGE);
#endif
}

static void watchdog_service(void)
{
    uint32 now = tick_count;
    if (now != tick_count_fed) {
        tick_count_fed = now;
#ifndef SFLR_NO_HW_WATCHDOG
        CyWdtClear();
#endif
    }
}

#define USB_PACKET 64u

static void tx_service(void)
{
    if (txq_head == txq_tail || USBUART_CDCIsReady() == 0u) {
        return;
    }
    uint8 chunk[USB_PACKET];
    uint16 n = 0u;
    uint8 s = CyEnterCriticalSection();
    while (txq_tail != txq_head && n < USB_PACKET - 1u) { /* < 64: no zero-length packet needed */
        chunk[n++] = txq[txq_tail];
        txq_tail = (uint16)((txq_tail + 1u) & (TXQ_SIZE - 1u));
    }
    CyExitCriticalSection(s);
    USBUART_PutData(chunk, n);
}

void hal_psoc5lp_poll(sflr_dev_t *dev)
{
    watchdog_service();
    if (USBUART_IsConfigurationChanged() != 0u && USBUART_GetConfiguration() != 0u) {
        (void)USBUART_CDC_Init(); /* (re)enumerated: arm the CDC OUT endpoint */
    }
    if (USBUART_GetConfiguration() == 0u) {
        return;
    }
    if (USBUART_DataIsReady() != 0u) {
        uint8 rx[USB_PACKET];
        uint16 n = USBUART_GetAll(rx);
        if (n > USB_PACKET) {
            n = USB_PACKET;
        }
        /* The tick interrupt must not run while a frame is handled (sflr_device.h). */
        uint8 s = CyEnterCriticalSection();
        sflr_rx_bytes(dev, rx, n);
        CyExitCriticalSection(s);
    }
    tx_service();
}
