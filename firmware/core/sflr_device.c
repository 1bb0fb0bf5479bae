/* sflr_device.c - protocol v1 device logic; see sflr_device.h and spec/protocol.md. */
#include "sflr_device.h"

#include <string.h>

#include "sflr_hal.h"

const sflr_config_t sflr_default_config = {
    500u, 255, 1024u, 10u, {'S', 'F', 'L', 'R', 0, 0, 0, 0}
};

static uint16_t sat_inc(uint16_t c) { return c == UINT16_MAX ? c : (uint16_t)(c + 1u); }

static int16_t sat_i16(int32_t x)
{
    return x > INT16_MAX ? INT16_MAX : (x < INT16_MIN ? INT16_MIN : (int16_t)x);
}

static void send(const sflr_msg_t *m)
{
    uint8_t frame[SFLR_FRAME_MAX];
    size_t n = sflr_encode(m, frame, sizeof frame);
    if (n > 0u) {
        hal_uart_write(frame, n);
    }
}

/* Drive the amplifier: the DAC goes to the 0 V code before the enable goes active
 * (an offset-binary DAC would otherwise drive full negative for a moment). */
static void apply(sflr_dev_t *d, int16_t v, bool enable)
{
    if (enable && !d->amp_on) {
        hal_dac_write(0);
        hal_amp_enable(true);
    } else if (!enable && d->amp_on) {
        hal_amp_enable(false);
    }
    d->amp_on = enable;
    hal_dac_write(v);
    d->out = v;
}

/* End of a run (STOP, or n_ticks reached): output 0 at once, amplifier off, report. */
static void finish(sflr_dev_t *d, uint8_t reason)
{
    apply(d, 0, false);
    d->state = SFLR_IDLE;
    sflr_msg_t m;
    memset(&m, 0, sizeof m);
    m.type = SFLR_STOPPED;
    m.u.stopped.reason = reason;
    m.u.stopped.ticks = d->k;
    m.u.stopped.late = d->late;
    m.u.stopped.watchdog_trips = d->watchdog_trips;
    m.u.stopped.rx_errors = d->rx_errors;
    send(&m);
}

void sflr_init(sflr_dev_t *d, const sflr_config_t *cfg)
{
    memset(d, 0, sizeof *d);
    d->cfg = *cfg;
    if (d->cfg.watchdog_ticks == 0u) {
        d->cfg.watchdog_ticks = 1u; /* 0 would trip before the first miss */
    }
    if (d->cfg.v_limit < 0) {
        d->cfg.v_limit = 0;
    }
    sflr_decoder_init(&d->rx);
    d->amp_on = true; /* force apply() to drive the enable low, whatever the pin did */
    apply(d, 0, false);
    d->state = SFLR_IDLE;
}

static void send_info(const sflr_dev_t *d)
{
    sflr_msg_t m;
    memset(&m, 0, sizeof m);
    m.type = SFLR_INFO;
    m.u.info.protocol_version = SFLR_PROTOCOL_VERSION;
    m.u.info.fw_major = SFLR_FW_MAJOR;
    m.u.info.fw_minor = SFLR_FW_MINOR;
    m.u.info.fw_patch = SFLR_FW_PATCH;
    m.u.info.rate_hz = d->cfg.rate_hz;
    m.u.info.v_limit = d->cfg.v_limit;
    m.u.info.counts_per_rev = d->cfg.counts_per_rev;
    m.u.info.watchdog_ticks = d->cfg.watchdog_ticks;
    memcpy(m.u.info.name, d->cfg.name, SFLR_NAME_LEN);
    send(&m);
}

/* Tick 0 comes next: zero the encoder now if START asked for it. */
static void begin_run(sflr_dev_t *d)
{
    if (d->reset_encoder) {
        hal_encoder_reset();
    }
    d->k = 0u;
    d->state = SFLR_RUNNING;
}

static void on_start(sflr_dev_t *d, uint8_t flags, uint32_t n_ticks)
{
    d->n_ticks = n_ticks;
    d->reset_encoder = (flags & SFLR_START_RESET_ENCODER) != 0u;
    d->k = 0u;
    d->misses = 0u;
    d->watchdog = false;
    d->expect_valid = false;
    d->cmd_ready = false;
    d->rx_error_flag = false;
    d->stale_flag = false;
    d->late = d->watchdog_trips = d->rx_errors = 0u;
    d->accel_sum = 0;
    d->accel_n = 0u;
    d->accel_offset = 0;
    apply(d, 0, true); /* 0 V, then enable: the amplifier settles before tick 0 */
    if (flags & SFLR_START_ZERO_ACCEL) {
        d->state = SFLR_ZEROING; /* 16 ticks of averaging, then tick 0 */
    } else {
        begin_run(d);
    }
}

static void on_command(sflr_dev_t *d, uint16_t seq, int16_t v)
{
    if (d->state == SFLR_IDLE) {
        return; /* no run: START clears every flag anyway */
    }
    if (d->state == SFLR_RUNNING && d->expect_valid && seq == d->expect_seq) {
        d->cmd_ready = true;
        d->cmd_v = v;
    } else {
        d->stale_flag = true; /* late, bogus or before SAMPLE 0: ignored, reported as STALE */
    }
}

static void handle(sflr_dev_t *d, const sflr_msg_t *m)
{
    switch (m->type) {
    case SFLR_COMMAND: on_command(d, m->u.command.seq, m->u.command.v); break;
    case SFLR_HELLO: send_info(d); break;
    case SFLR_START: on_start(d, m->u.start.flags, m->u.start.n_ticks); break;
    case SFLR_STOP: finish(d, SFLR_REASON_STOP); break;
    default: break; /* device->station messages: not addressed to us */
    }
}

void sflr_rx_bytes(sflr_dev_t *d, const uint8_t *data, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        sflr_msg_t m;
        sflr_result_t r = sflr_decoder_push(&d->rx, data[i], &m);
        if (r == SFLR_OK) {
            handle(d, &m);
        } else if (sflr_is_error(r)) {
            d->rx_errors = sat_inc(d->rx_errors);
            d->rx_error_flag = true;
        }
    }
}

/* Round sum/n to the nearest integer, halves away from zero (no signed shifts). */
static int16_t div_round(int32_t sum, int32_t n)
{
    int32_t q = sum >= 0 ? (sum + n / 2) / n : -((-sum + n / 2) / n);
    return sat_i16(q);
}

static void zeroing_tick(sflr_dev_t *d)
{
    d->accel_sum += hal_accel_read();
    if (++d->accel_n == SFLR_ZERO_READINGS) {
        d->accel_offset = div_round(d->accel_sum, SFLR_ZERO_READINGS);
        begin_run(d);
    }
}

void sflr_tick(sflr_dev_t *d)
{
    if (d->state == SFLR_IDLE) {
        return;
    }
    if (d->state == SFLR_ZEROING) {
        zeroing_tick(d);
        return;
    }
    uint8_t status = 0u;
    int16_t v;

    /* (1) Choose the output. */
    if (d->k == 0u) {
        v = 0; /* tick 0 outputs 0 and is never LATE */
    } else if (d->cmd_ready) {
        v = d->cmd_v; /* the COMMAND with seq k-1 */
        d->misses = 0u;
        if (d->watchdog) { /* the expected seq ends the trip */
            d->watchdog = false;
            d->watchdog_trips = sat_inc(d->watchdog_trips);
        }
    } else {
        status |= SFLR_ST_LATE; /* hold the last output */
        d->late = sat_inc(d->late);
        d->misses = sat_inc(d->misses);
        if (d->misses >= d->cfg.watchdog_ticks) {
            d->watchdog = true; /* from the watchdog_ticks-th consecutive miss on: 0 */
        }
        v = d->watchdog ? 0 : d->out;
    }
    if (d->watchdog) {
        status |= SFLR_ST_WATCHDOG;
    }
    if (v > d->cfg.v_limit) {
        v = d->cfg.v_limit;
        status |= SFLR_ST_SATURATED;
    } else if (v < -d->cfg.v_limit) {
        v = (int16_t)-d->cfg.v_limit;
        status |= SFLR_ST_SATURATED;
    }

    /* (2) Apply it; the amplifier is disabled while WATCHDOG is set. */
    apply(d, v, !d->watchdog);

    /* (3) Latch the sensors. */
    int32_t theta = hal_encoder_read();
    int16_t accel = sat_i16((int32_t)hal_accel_read() - d->accel_offset);

    /* (4) Send SAMPLE k. */
    if (d->rx_error_flag) {
        status |= SFLR_ST_RX_ERROR;
    }
    if (d->stale_flag) {
        status |= SFLR_ST_STALE;
    }
    d->rx_error_flag = d->stale_flag = false;

    sflr_msg_t m;
    memset(&m, 0, sizeof m);
    m.type = SFLR_SAMPLE;
    m.u.sample.seq = (uint16_t)(d->k & 0xFFFFu);
    m.u.sample.theta = theta;
    m.u.sample.accel = accel;
    m.u.sample.v_applied = v;
    m.u.sample.status = status;
    send(&m);

    /* Only a COMMAND answering this sample may act at tick k+1. */
    d->expect_seq = m.u.sample.seq;
    d->expect_valid = true;
    d->cmd_ready = false;
    d->k++;
    if (d->n_ticks != 0u && d->k == d->n_ticks) {
        finish(d, SFLR_REASON_DONE); /* right after SAMPLE n_ticks-1, in the same tick */
    }
}
