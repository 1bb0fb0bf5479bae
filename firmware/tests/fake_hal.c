/* fake_hal.c - see fake_hal.h */
#include "fake_hal.h"

#include <string.h>

#include "sflr_hal.h"

int32_t fake_encoder;
int16_t fake_accel;
int16_t fake_dac;
bool fake_amp;
unsigned fake_encoder_resets;
unsigned fake_unsafe_enables;
int fake_events[64];
unsigned fake_n_events;

static uint8_t tx[1 << 16];
static size_t tx_len;

static void event(int e)
{
    if (fake_n_events == 64u) { /* keep the most recent ones */
        memmove(fake_events, fake_events + 1, sizeof fake_events - sizeof fake_events[0]);
        fake_n_events--;
    }
    fake_events[fake_n_events++] = e;
}

void fake_reset(void)
{
    fake_encoder = 0;
    fake_accel = 0;
    fake_dac = 0x5A5A; /* not 0: init must write the 0 V code itself */
    fake_amp = true;   /* and drive the enable inactive itself */
    fake_encoder_resets = 0;
    fake_unsafe_enables = 0;
    fake_n_events = 0;
    tx_len = 0;
}

int32_t hal_encoder_read(void) { return fake_encoder; }
void hal_encoder_reset(void) { fake_encoder = 0; fake_encoder_resets++; }
int16_t hal_accel_read(void) { return fake_accel; }
void hal_dac_write(int16_t v) { fake_dac = v; event(v); }
void hal_amp_enable(bool on)
{
    if (on && !fake_amp && fake_dac != 0) {
        fake_unsafe_enables++;
    }
    fake_amp = on;
    event(on ? FAKE_AMP_ON : FAKE_AMP_OFF);
}
void hal_uart_write(const uint8_t *data, size_t n)
{
    if (tx_len + n <= sizeof tx) {
        memcpy(tx + tx_len, data, n);
        tx_len += n;
    } else {
        printf("fake_hal: tx buffer full\n");
        t_failed++;
    }
}

int fake_take(sflr_msg_t *out, int max)
{
    sflr_decoder_t d;
    sflr_decoder_init(&d);
    int n = 0;
    for (size_t i = 0; i < tx_len; i++) {
        sflr_msg_t m;
        sflr_result_t r = sflr_decoder_push(&d, tx[i], &m);
        if (r == SFLR_OK && n < max) {
            out[n++] = m;
        } else if (r != SFLR_PENDING) {
            printf("fake_hal: device sent a bad frame (result %d)\n", (int)r);
            t_failed++;
        }
    }
    if (d.len != 0u) {
        printf("fake_hal: device sent an unterminated frame\n");
        t_failed++;
    }
    tx_len = 0;
    return n;
}

