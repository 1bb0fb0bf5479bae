/* test_psoc_hal.c - the PSoC 5LP HAL (psoc5lp/hal_psoc5lp.c) on the host, against fakes
 * of the component APIs declared in psoc5lp/stubs: the DAC mapping (+-255 counts =
 * +-2.5 V, 0 counts = 0 V), the amplifier-enable level and reset order, the transmit
 * queue (whole frames, drop when full, never block) and the received-bytes path. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "hal_psoc5lp.h"
#include "project.h"
#include "sflr_hal.h"

/* The wiring options of hal_psoc5lp.c; the Makefile builds this test twice, with the
 * defaults and with every sign and level flipped (test_psoc_hal_flipped). */
#include "hal_wiring.h"
#define AMP_ON_LEVEL ((int)(AMP_EN_ACTIVE))
#define AMP_OFF_LEVEL ((int)(AMP_EN_ACTIVE ^ 1u))

/* ---- fakes of the component APIs ---- */
static uint16 dac_p, dac_n;
static int dac_started, amp_level = -1, amp_writes_before_dac_start;
static int32 quad_count;
static int16 adc_result;
static uint8 usb_config = 1, usb_ready = 1;
static uint8 usb_rx[64];
static uint16 usb_rx_len;
static uint8 usb_tx[4096];
static size_t usb_tx_len;
static unsigned crit_depth, crit_max;

static int wdt_started = -1;
static unsigned wdt_clears, ilo_1k;
void CyILO_Start1K(void) { ilo_1k++; }
void CyWdtStart(uint8 ticks, uint8 lp) { (void)lp; wdt_started = ticks; }
void CyWdtClear(void) { wdt_clears++; }
uint8 CyEnterCriticalSection(void) { crit_depth++; crit_max = crit_depth > crit_max ? crit_depth : crit_max; return 0; }
void CyExitCriticalSection(uint8 s) { (void)s; crit_depth--; }
void QuadDec_Start(void) {}
void QuadDec_Stop(void) {}
int32 QuadDec_GetCounter(void) { return quad_count; }
void QuadDec_SetCounter(int32 v) { quad_count = v; }
void ADC_Start(void) {}
void ADC_Stop(void) {}
void ADC_StartConvert(void) {}
void ADC_StopConvert(void) {}
uint8 ADC_IsEndConversion(uint8 m) { (void)m; return 1; }
int16 ADC_GetResult16(void) { return adc_result; }
void DAC_P_Start(void) { dac_started++; }
void DAC_P_Stop(void) {}
void DAC_P_SetValue(uint16 v) { dac_p = v; }
void DAC_N_Start(void) { dac_started++; }
void DAC_N_Stop(void) {}
void DAC_N_SetValue(uint16 v) { dac_n = v; }
void BUF_P_Start(void) {}
void BUF_P_Stop(void) {}
void BUF_N_Start(void) {}
void BUF_N_Stop(void) {}
void AMP_EN_Write(uint8 v) { amp_level = v; amp_writes_before_dac_start += dac_started == 0; }
uint8 AMP_EN_Read(void) { return (uint8)amp_level; }
void Clock_tick_Start(void) {}
void Clock_tick_Stop(void) {}
uint8 USBUART_GetConfiguration(void) { return usb_config; }
uint8 USBUART_IsConfigurationChanged(void) { return 0; }
uint8 USBUART_CDC_Init(void) { return 0; }
uint8 USBUART_DataIsReady(void) { return usb_rx_len != 0u; }
uint16 USBUART_GetCount(void) { return usb_rx_len; }
uint16 USBUART_GetAll(uint8 p[]) { uint16 n = usb_rx_len; memcpy(p, usb_rx, n); usb_rx_len = 0; return n; }
uint8 USBUART_CDCIsReady(void) { return usb_ready; }
void USBUART_PutData(const uint8 p[], uint16 n)
{
    CHECK(n > 0u && n < 64u && crit_depth == 0u); /* never from inside a critical section */
    memcpy(usb_tx + usb_tx_len, p, n);
    usb_tx_len += n;
}

/* Differential output. A 12-bit DVDAC in its 0-4.080 V range takes codes 0..0xFF0
 * (16 sub-steps of the VDAC8's 16 mV step): 1 mV per code, not 4.080 V / 4096. */
#define DVDAC_MAX 0xFF0u
static double volts(void)
{
    return ((double)dac_p - (double)dac_n) * 1e-3;
}

int main(void)
{
    hal_psoc5lp_init();
    CHECK(amp_level == AMP_OFF_LEVEL && amp_writes_before_dac_start == 1); /* disabled before anything */
    CHECK(dac_p == 2048 && dac_n == 2048);                    /* 0 V */

    /* mapping: +-255 counts = +-2.5 V within half a DVDAC step per side, monotonic */
    double worst = 0, prev = -10;
    int monotonic = 1, in_range = 1;
    for (int v = -255; v <= 255; v++) {
        hal_dac_write((int16_t)v);
        double err = fabs(volts() - v * 2.5 / 255.0);
        worst = err > worst ? err : worst;
        monotonic &= volts() > prev;
        prev = volts();
        in_range &= dac_p <= DVDAC_MAX && dac_n <= DVDAC_MAX && abs(dac_p + dac_n - 4096) <= 1; /* common mode at mid */
    }
    CHECK(worst <= 0.5e-3 + 1e-9); /* nearest code: within half a code (0.5 mV) */
    CHECK(monotonic && in_range);
    hal_dac_write(255); /* full scale is exactly 2500 codes: 2.500 V */
    CHECK(dac_p - dac_n == 2500 && dac_p == 2048 + 1250);
    hal_dac_write(-300); /* beyond the DAC's range: saturates at -2.5 V, no wrap */
    CHECK(dac_n - dac_p == 2500);
    hal_dac_write(INT16_MAX);
    CHECK(dac_p - dac_n == 2500);
    hal_dac_write(1); /* one count = 9.804 mV -> 10 codes */
    CHECK(dac_p - dac_n == 10);

    hal_amp_enable(true);
    CHECK(amp_level == AMP_ON_LEVEL);
    hal_amp_enable(false);
    CHECK(amp_level == AMP_OFF_LEVEL);
    quad_count = -1234;
    CHECK(hal_encoder_read() == ENCODER_SIGN * -1234);
    hal_encoder_reset();
    CHECK(quad_count == 0);
    adc_result = -3;
    CHECK(hal_accel_read() == ACCEL_SIGN * -3);
    adc_result = INT16_MIN; /* a saturated ADC keeps its sign when flipped: no wrap */
    CHECK(hal_accel_read() == (ACCEL_SIGN > 0 ? INT16_MIN : INT16_MAX));
    adc_result = INT16_MAX;
    CHECK(hal_accel_read() == (ACCEL_SIGN > 0 ? INT16_MAX : -INT16_MAX));

    /* transmit queue: whole frames or nothing, drained in < 64-byte USB packets */
    uint8_t frame[16];
    for (int i = 0; i < 16; i++) {
        frame[i] = (uint8_t)(i + 1);
    }
    frame[15] = 0;
    usb_ready = 0;
    for (int i = 0; i < 40; i++) { /* 640 bytes into a 511-byte queue */
        hal_uart_write(frame, sizeof frame);
    }
    sflr_dev_t dev;
    sflr_init(&dev, &sflr_default_config);
    hal_psoc5lp_poll(&dev);
    CHECK(usb_tx_len == 0u); /* USB busy: nothing sent, nothing blocked */
    usb_ready = 1;
    for (int i = 0; i < 20; i++) {
        hal_psoc5lp_poll(&dev);
    }
    CHECK(usb_tx_len == 31u * 16u); /* 31 whole frames fitted, the rest were dropped */
    int intact = 1;
    for (size_t i = 0; i < usb_tx_len; i++) {
        intact &= usb_tx[i] == frame[i % 16];
    }
    CHECK(intact);

    /* received bytes reach the core inside a critical section: HELLO -> INFO */
    usb_tx_len = 0;
    crit_max = 0;
    const uint8_t hello[] = {0x05, 0x03, 0x01, 0x7d, 0x58, 0x00}; /* the HELLO vector */
    memcpy(usb_rx, hello, sizeof hello);
    usb_rx_len = sizeof hello;
    hal_psoc5lp_poll(&dev);
    hal_psoc5lp_poll(&dev);
    CHECK(crit_max >= 1u && crit_depth == 0u);
    CHECK(usb_tx_len == 24u && usb_tx[1] == SFLR_INFO && usb_tx[23] == 0u);

    /* hardware watchdog: started (32-48 ms), fed by the main loop only while ticks run */
    hal_psoc5lp_watchdog_start();
    CHECK(wdt_started == CYWDT_16_TICKS && ilo_1k == 1u);
    unsigned c0 = wdt_clears;
    hal_psoc5lp_poll(&dev);
    hal_psoc5lp_poll(&dev);
    CHECK(wdt_clears == c0); /* no tick since the last feed: a stopped interrupt starves it */
    hal_psoc5lp_tick(&dev);
    hal_psoc5lp_poll(&dev);
    hal_psoc5lp_poll(&dev);
    CHECK(wdt_clears == c0 + 1u);
    hal_psoc5lp_tick(&dev);
    hal_psoc5lp_tick(&dev);
    hal_psoc5lp_poll(&dev);
    CHECK(wdt_clears == c0 + 2u);
    return t_finish();
}
