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
unsigned t_passed, t_failed;

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

bool msg_eq(const sflr_msg_t *a, const sflr_msg_t *b)
{
    if (a->type != b->type) {
        return false;
    }
    switch (a->type) {
    case SFLR_SAMPLE:
        return a->u.sample.seq == b->u.sample.seq && a->u.sample.theta == b->u.sample.theta &&
               a->u.sample.accel == b->u.sample.accel && a->u.sample.v_applied == b->u.sample.v_applied &&
               a->u.sample.status == b->u.sample.status;
    case SFLR_COMMAND:
        return a->u.command.seq == b->u.command.seq && a->u.command.v == b->u.command.v;
    case SFLR_HELLO:
        return a->u.hello.protocol_version == b->u.hello.protocol_version;
    case SFLR_INFO:
        return a->u.info.protocol_version == b->u.info.protocol_version &&
               a->u.info.fw_major == b->u.info.fw_major && a->u.info.fw_minor == b->u.info.fw_minor &&
               a->u.info.fw_patch == b->u.info.fw_patch && a->u.info.rate_hz == b->u.info.rate_hz &&
               a->u.info.v_limit == b->u.info.v_limit && a->u.info.counts_per_rev == b->u.info.counts_per_rev &&
               a->u.info.watchdog_ticks == b->u.info.watchdog_ticks &&
               memcmp(a->u.info.name, b->u.info.name, SFLR_NAME_LEN) == 0;
    case SFLR_START:
        return a->u.start.flags == b->u.start.flags && a->u.start.n_ticks == b->u.start.n_ticks;
    case SFLR_STOP:
        return true;
    case SFLR_STOPPED:
        return a->u.stopped.reason == b->u.stopped.reason && a->u.stopped.ticks == b->u.stopped.ticks &&
               a->u.stopped.late == b->u.stopped.late && a->u.stopped.watchdog_trips == b->u.stopped.watchdog_trips &&
               a->u.stopped.rx_errors == b->u.stopped.rx_errors;
    default:
        return false;
    }
}

int t_finish(void)
{
    printf("%u passed, %u failed\n", t_passed, t_failed);
    return t_failed == 0u ? 0 : 1;
}
