/* test_core.c - the core against the protocol v1 vectors and the spec's tick rules. */
#include <string.h>

#include "fake_hal.h"
#include "sflr_device.h"
#include "sflr_proto.h"
#include "vectors.h"

#define N_OF(a) (sizeof(a) / sizeof((a)[0]))

/* ---------------------------------------------------------------- framing */

static void test_crc(void)
{
    /* The CRC-16/CCITT-FALSE check value of "123456789" is 0x29B1. */
    CHECK(sflr_crc16((const uint8_t *)"123456789", 9) == 0x29B1u);
    CHECK(sflr_crc16(NULL, 0) == 0xFFFFu);
}

static void test_cobs(void)
{
    uint8_t in[600], enc[620], dec[600];
    for (size_t i = 0; i < sizeof in; i++) {
        in[i] = (i % 97 == 0 || (i > 300 && i < 310)) ? 0u : (uint8_t)(i * 7u + 1u);
    }
    /* long zero-free runs (> 254) exercise the 0xFF block code */
    for (size_t n = 0; n <= sizeof in; n += (n < 20 ? 1 : 37)) {
        size_t e = sflr_cobs_encode(in, n, enc, sizeof enc);
        CHECK(e >= n + 1);
        CHECK(memchr(enc, 0, e) == NULL);
        int d = sflr_cobs_decode(enc, e, dec, sizeof dec);
        CHECK(d == (int)n);
        CHECK(d >= 0 && memcmp(in, dec, (size_t)d) == 0);
    }
    uint8_t ones[300];
    memset(ones, 0x11, sizeof ones);
    size_t e = sflr_cobs_encode(ones, sizeof ones, enc, sizeof enc);
    CHECK(enc[0] == 0xFFu);
    CHECK(sflr_cobs_decode(enc, e, dec, sizeof dec) == 300);
    CHECK(sflr_cobs_encode(ones, 10, enc, 10) == 0);       /* no room for the code byte */
    CHECK(sflr_cobs_decode(enc, e, dec, 299) == -1);         /* output would overflow */
    const uint8_t bad[] = {0x03, 0x11, 0x00, 0x22};          /* zero inside a frame */
    CHECK(sflr_cobs_decode(bad, sizeof bad, dec, sizeof dec) == -1);
}

static void test_valid_vectors(void)
{
    for (size_t i = 0; i < N_OF(VALID); i++) {
        const valid_vec_t *v = &VALID[i];
        uint8_t out[SFLR_FRAME_MAX];
        size_t n = sflr_encode(&v->msg, out, sizeof out);
        CHECK(n == v->len);
        CHECK(n == v->len && memcmp(out, v->frame, n) == 0);
        sflr_msg_t m;
        CHECK(sflr_frame_decode(v->frame, v->len - 1, &m) == SFLR_OK);
        CHECK(msg_eq(&m, &v->msg));
        /* incremental: PENDING for every byte, then the message at the delimiter */
        sflr_decoder_t d;
        sflr_decoder_init(&d);
        int pending = 0;
        sflr_result_t r = SFLR_PENDING;
        for (size_t k = 0; k < v->len; k++) {
            r = sflr_decoder_push(&d, v->frame[k], &m);
            pending += r == SFLR_PENDING;
        }
        CHECK(pending == (int)v->len - 1);
        CHECK(r == SFLR_OK && msg_eq(&m, &v->msg));
        CHECK(sflr_encode(&v->msg, out, v->len - 1) == 0); /* one byte short */
    }
    sflr_msg_t unknown;
    memset(&unknown, 0, sizeof unknown);
    unknown.type = 0x55;
    uint8_t out[SFLR_FRAME_MAX];
    CHECK(sflr_encode(&unknown, out, sizeof out) == 0);
}

static void test_invalid_vectors(void)
{
    for (size_t i = 0; i < N_OF(INVALID); i++) {
        const invalid_vec_t *v = &INVALID[i];
        sflr_msg_t m;
        sflr_result_t r = sflr_frame_decode(v->frame, v->len - 1, &m);
        if (r != v->result) {
            printf("invalid vector '%s': result %d, expected %d\n", v->why, (int)r, (int)v->result);
        }
        CHECK(r == v->result);
        CHECK(sflr_is_error(r) == (v->counts == 1));
        /* through the device: no message, the error counted unless empty */
        fake_reset();
        sflr_dev_t dev;
        sflr_init(&dev, &sflr_default_config);
        fake_take(&m, 1);
        sflr_rx_bytes(&dev, v->frame, v->len);
        CHECK(dev.rx_errors == (uint16_t)v->counts);
        CHECK(fake_take(&m, 1) == 0);
    }
}

static int decode_stream(const uint8_t *p, size_t n, size_t chunk, sflr_msg_t *out, int max, int *errors)
{
    sflr_decoder_t d;
    sflr_decoder_init(&d);
    int got = 0;
    *errors = 0;
    for (size_t i = 0; i < n; i += chunk) { /* chunking must not matter */
        for (size_t k = i; k < i + chunk && k < n; k++) {
            sflr_msg_t m;
            sflr_result_t r = sflr_decoder_push(&d, p[k], &m);
            if (r == SFLR_OK && got < max) {
                out[got++] = m;
            }
            *errors += sflr_is_error(r);
        }
    }
    return got;
}

static void test_stream(void)
{
    for (size_t chunk = 1; chunk <= STREAM_LEN; chunk++) {
        sflr_msg_t got[8];
        int errors;
        int n = decode_stream(STREAM, STREAM_LEN, chunk, got, 8, &errors);
        CHECK(n == (int)N_OF(STREAM_DECODED));
        for (int i = 0; i < n && i < (int)N_OF(STREAM_DECODED); i++) {
            CHECK(msg_eq(&got[i], &STREAM_DECODED[i]));
        }
        /* the leading garbage and the corrupted frame are the two dropped frames */
        CHECK(errors == 2);
    }
}

static void test_overlong(void)
{
    /* 200 bytes of line noise, its delimiter, then a good frame */
    uint8_t s[201 + 24];
    memset(s, 0x42, 200);
    s[200] = 0x00;
    size_t n = sflr_encode(&VALID[0].msg, s + 201, 24);
    CHECK(n == 16);
    sflr_msg_t got[4];
    int errors;
    CHECK(decode_stream(s, 201 + n, 1, got, 4, &errors) == 1);
    CHECK(errors == 1);
    CHECK(msg_eq(&got[0], &VALID[0].msg));
    /* 63 bytes is the longest frame body; 64 is over the limit */
    uint8_t raw[SFLR_FRAME_MAX];
    memset(raw, 0x01, sizeof raw);
    sflr_msg_t m;
    CHECK(sflr_frame_decode(raw, SFLR_FRAME_MAX, &m) == SFLR_ERR_OVERLONG);
    CHECK(sflr_frame_decode(raw, SFLR_FRAME_MAX - 1, &m) == SFLR_ERR_LENGTH ||
          sflr_frame_decode(raw, SFLR_FRAME_MAX - 1, &m) == SFLR_ERR_CRC);
}

/* ---------------------------------------------------------------- device */

static sflr_dev_t dev;

static void feed(const sflr_msg_t *m)
{
    uint8_t f[SFLR_FRAME_MAX];
    size_t n = sflr_encode(m, f, sizeof f);
    sflr_rx_bytes(&dev, f, n);
}
static void send_command(uint16_t seq, int16_t v)
{
    sflr_msg_t m = { .type = SFLR_COMMAND, .u.command = { .seq = seq, .v = v } };
    feed(&m);
}
static void send_start(uint8_t flags, uint32_t n_ticks)
{
    sflr_msg_t m = { .type = SFLR_START, .u.start = { .flags = flags, .n_ticks = n_ticks } };
    feed(&m);
}
static void send_simple(uint8_t type)
{
    sflr_msg_t m = { .type = type, .u.hello = { .protocol_version = 1 } };
    feed(&m);
}

/* One tick that must produce exactly one SAMPLE; checks the safety invariants. */
static sflr_msg_t tick_sample(void)
{
    sflr_msg_t m[4];
    memset(m, 0, sizeof m);
    sflr_tick(&dev);
    int n = fake_take(m, 4);
    CHECK(n == 1 && m[0].type == SFLR_SAMPLE);
    CHECK(m[0].u.sample.v_applied == fake_dac);                 /* reports what it applied */
    CHECK(fake_amp == !(m[0].u.sample.status & SFLR_ST_WATCHDOG)); /* off while WATCHDOG */
    CHECK(m[0].u.sample.v_applied <= dev.cfg.v_limit && m[0].u.sample.v_applied >= -dev.cfg.v_limit);
    return m[0];
}

static void fresh(const sflr_config_t *cfg)
{
    fake_reset();
    sflr_init(&dev, cfg);
}

/* The last enable event was preceded by a DAC write of 0 V. */
static bool zero_before_last_enable(void)
{
    for (unsigned i = fake_n_events; i-- > 0;) {
        if (fake_events[i] == FAKE_AMP_ON) {
            return i > 0 && fake_events[i - 1] == 0;
        }
    }
    return false;
}

static void test_reset_and_hello(void)
{
    fresh(&sflr_default_config);
    CHECK(fake_dac == 0 && !fake_amp); /* safe from reset */
    sflr_msg_t m[4];
    sflr_tick(&dev);
    CHECK(fake_take(m, 4) == 0); /* idle: no samples */
    send_simple(SFLR_HELLO);
    CHECK(fake_take(m, 4) == 1);
    CHECK(msg_eq(&m[0], &VALID[8].msg)); /* the INFO vector is the rig's default config */
    CHECK(!fake_amp);
    /* HELLO is answered at any time, also during a run */
    send_start(0, 0);
    tick_sample();
    send_simple(SFLR_HELLO);
    CHECK(fake_take(m, 4) == 1 && m[0].type == SFLR_INFO);
    CHECK(tick_sample().u.sample.seq == 1);
}

static void test_start_tick0_and_delay(void)
{
    fresh(&sflr_default_config);
    fake_encoder = 777;
    send_start(0, 0);
    CHECK(fake_amp && fake_dac == 0);
    CHECK(zero_before_last_enable()); /* 0 V before the enable goes active */
    CHECK(fake_unsafe_enables == 0);
    CHECK(fake_encoder_resets == 0); /* bit0 clear: encoder kept */

    sflr_msg_t s = tick_sample(); /* tick 0: outputs 0, never LATE */
    CHECK(s.u.sample.seq == 0 && s.u.sample.v_applied == 0 && s.u.sample.status == 0);
    CHECK(s.u.sample.theta == 777);

    send_command(0, 50);
    CHECK(fake_dac == 0); /* a command acts from the next tick, not on arrival */
    s = tick_sample();
    CHECK(s.u.sample.seq == 1 && s.u.sample.v_applied == 50 && s.u.sample.status == 0);
    CHECK(fake_dac == 50);

    send_command(1, -70);
    CHECK(fake_dac == 50);
    fake_encoder = 780;
    fake_accel = -5;
    s = tick_sample();
    CHECK(s.u.sample.v_applied == -70 && s.u.sample.theta == 780 && s.u.sample.accel == -5);
    CHECK(s.u.sample.status == 0);
}

static void test_late_hold_and_watchdog(uint8_t wd)
{
    sflr_config_t cfg = sflr_default_config;
    cfg.watchdog_ticks = wd;
    fresh(&cfg);
    send_start(SFLR_START_RESET_ENCODER, 0);
    tick_sample();
    send_command(0, 120);
    CHECK(tick_sample().u.sample.v_applied == 120);
    /* misses 1 .. wd-1: hold and LATE */
    for (unsigned miss = 1; miss < wd; miss++) {
        sflr_msg_t s = tick_sample();
        CHECK(s.u.sample.v_applied == 120 && s.u.sample.status == SFLR_ST_LATE);
        CHECK(fake_amp);
    }
    /* the wd-th consecutive miss and every later one: 0, LATE|WATCHDOG, amplifier off */
    for (unsigned miss = wd; miss < wd + 5u; miss++) {
        sflr_msg_t s = tick_sample();
        CHECK(s.u.sample.v_applied == 0);
        CHECK(s.u.sample.status == (SFLR_ST_LATE | SFLR_ST_WATCHDOG));
        CHECK(!fake_amp && fake_dac == 0);
    }
    CHECK(dev.late == wd + 4u);
    /* the expected seq ends the trip: output, amplifier back (0 V first), one trip */
    uint16_t seq = (uint16_t)(dev.k - 1u);
    send_command(seq, 33);
    sflr_msg_t s = tick_sample();
    CHECK(s.u.sample.v_applied == 33 && s.u.sample.status == 0);
    CHECK(fake_amp && fake_unsafe_enables == 0);
    CHECK(fake_n_events >= 3 && fake_events[fake_n_events - 3] == 0 &&
          fake_events[fake_n_events - 2] == FAKE_AMP_ON && fake_events[fake_n_events - 1] == 33);
    /* a fresh miss count: one miss is only LATE again (or trips at once when wd == 1) */
    s = tick_sample();
    if (wd > 1u) {
        CHECK(s.u.sample.status == SFLR_ST_LATE && s.u.sample.v_applied == 33);
    } else {
        CHECK(s.u.sample.status == (SFLR_ST_LATE | SFLR_ST_WATCHDOG) && s.u.sample.v_applied == 0);
    }
    send_simple(SFLR_STOP);
    sflr_msg_t m[2];
    CHECK(fake_take(m, 2) == 1 && m[0].type == SFLR_STOPPED);
    CHECK(m[0].u.stopped.watchdog_trips == 1 && m[0].u.stopped.late == wd + 5u);
    CHECK(m[0].u.stopped.reason == SFLR_REASON_STOP && m[0].u.stopped.ticks == wd + 8u);
}

static void test_clamp(void)
{
    sflr_config_t cfg = sflr_default_config;
    cfg.v_limit = 200;
    fresh(&cfg);
    send_start(0, 0);
    tick_sample();
    const int16_t in[] = {300, -300, 200, -200, 201, INT16_MIN, INT16_MAX, 0};
    const int16_t out[] = {200, -200, 200, -200, 200, -200, 200, 0};
    for (size_t i = 0; i < N_OF(in); i++) {
        send_command((uint16_t)(dev.k - 1u), in[i]);
        sflr_msg_t s = tick_sample();
        CHECK(s.u.sample.v_applied == out[i]);
        CHECK(((s.u.sample.status & SFLR_ST_SATURATED) != 0) == (in[i] != out[i]));
    }
    /* a held output stays clamped and is not re-flagged */
    sflr_msg_t s = tick_sample();
    CHECK(s.u.sample.v_applied == 0 && s.u.sample.status == SFLR_ST_LATE);
}

static void test_stale_and_rx_error(void)
{
    fresh(&sflr_default_config);
    send_command(0, 10); /* idle: ignored, no flag */
    send_start(0, 0);
    send_command(0, 10); /* before SAMPLE 0: answers nothing */
    sflr_msg_t s = tick_sample();
    CHECK(s.u.sample.status == SFLR_ST_STALE && s.u.sample.v_applied == 0);
    send_command(0, 40);
    CHECK(tick_sample().u.sample.v_applied == 40);
    send_command(0, 99); /* late answer to sample 0 after sample 1 went out */
    send_command(7, 99); /* from the future */
    s = tick_sample();
    CHECK(s.u.sample.status == (SFLR_ST_STALE | SFLR_ST_LATE) && s.u.sample.v_applied == 40);
    send_command(2, 41);
    s = tick_sample();
    CHECK(s.u.sample.status == 0 && s.u.sample.v_applied == 41); /* STALE cleared */

    const uint8_t garbage[] = {0x13, 0x37, 0x00};
    sflr_rx_bytes(&dev, garbage, sizeof garbage);
    send_command(3, 42);
    s = tick_sample();
    CHECK(s.u.sample.status == SFLR_ST_RX_ERROR && s.u.sample.v_applied == 42);
    const uint8_t empty[] = {0x00, 0x00};
    sflr_rx_bytes(&dev, empty, sizeof empty);
    send_command(4, 43);
    s = tick_sample();
    CHECK(s.u.sample.status == 0); /* empty frames are not errors */
    CHECK(dev.rx_errors == 1);
}

static void test_stop(void)
{
    fresh(&sflr_default_config);
    send_start(0, 0);
    tick_sample();
    send_command(0, 150);
    tick_sample();
    const uint8_t garbage[] = {0x05, 0x00};
    sflr_rx_bytes(&dev, garbage, sizeof garbage);
    tick_sample(); /* LATE */
    CHECK(fake_dac == 150 && fake_amp);
    send_simple(SFLR_STOP);
    CHECK(fake_dac == 0 && !fake_amp); /* at once, not at the next tick */
    sflr_msg_t m[2];
    CHECK(fake_take(m, 2) == 1);
    sflr_msg_t want = { .type = SFLR_STOPPED,
                        .u.stopped = { .reason = 0, .ticks = 3, .late = 1, .watchdog_trips = 0, .rx_errors = 1 } };
    CHECK(msg_eq(&m[0], &want));
    sflr_tick(&dev);
    CHECK(fake_take(m, 2) == 0); /* no samples after STOP */
    send_command(2, 100);
    sflr_tick(&dev);
    CHECK(fake_dac == 0 && !fake_amp);
    send_simple(SFLR_STOP); /* STOP when idle is still answered */
    CHECK(fake_take(m, 2) == 1 && m[0].type == SFLR_STOPPED && m[0].u.stopped.ticks == 3);
}

static void test_n_ticks(void)
{
    fresh(&sflr_default_config);
    send_start(0, 5);
    for (uint16_t k = 0; k < 4; k++) {
        sflr_msg_t s = tick_sample();
        CHECK(s.u.sample.seq == k);
        send_command(k, (int16_t)(10 * (k + 1)));
    }
    /* tick 4 = n_ticks - 1: SAMPLE 4, then STOPPED reason 1 at once, in the same tick */
    sflr_msg_t m[3];
    sflr_tick(&dev);
    CHECK(fake_take(m, 3) == 2);
    CHECK(m[0].type == SFLR_SAMPLE && m[0].u.sample.seq == 4 && m[0].u.sample.v_applied == 40);
    sflr_msg_t want = { .type = SFLR_STOPPED,
                        .u.stopped = { .reason = 1, .ticks = 5, .late = 0, .watchdog_trips = 0, .rx_errors = 0 } };
    CHECK(msg_eq(&m[1], &want));
    CHECK(fake_dac == 0 && !fake_amp);
    sflr_tick(&dev);
    CHECK(fake_take(m, 3) == 0);
}

static void test_zero_accel(void)
{
    fresh(&sflr_default_config);
    fake_encoder = 500;
    send_start(SFLR_START_RESET_ENCODER | SFLR_START_ZERO_ACCEL, 0);
    CHECK(fake_amp && fake_dac == 0 && fake_unsafe_enables == 0);
    sflr_msg_t m[2];
    /* 16 readings averaging -2.5: rounds half away from zero to -3 */
    for (int i = 0; i < 16; i++) {
        fake_accel = (int16_t)(i % 2 ? -2 : -3);
        sflr_tick(&dev);
        CHECK(fake_take(m, 2) == 0); /* no samples while averaging */
        CHECK(fake_encoder_resets == (i == 15 ? 1u : 0u)); /* encoder zeroed just before tick 0 */
    }
    fake_accel = -2;
    fake_encoder += 3;
    sflr_msg_t s = tick_sample();
    CHECK(s.u.sample.seq == 0 && s.u.sample.accel == 1 && s.u.sample.theta == 3);
    CHECK(s.u.sample.status == 0 && s.u.sample.v_applied == 0);
    fake_accel = INT16_MIN; /* offset subtraction saturates instead of wrapping */
    s = tick_sample();
    CHECK(s.u.sample.accel == INT16_MIN + 3);
    /* positive average 2.5 -> 3 */
    send_start(SFLR_START_ZERO_ACCEL, 0);
    CHECK(fake_encoder_resets == 1u);
    for (int i = 0; i < 16; i++) {
        fake_accel = (int16_t)(i % 2 ? 2 : 3);
        sflr_tick(&dev);
    }
    fake_take(m, 2);
    fake_accel = 3;
    CHECK(tick_sample().u.sample.accel == 0);
    CHECK(fake_encoder_resets == 1u); /* bit0 clear */
    /* START bit0 alone zeroes the encoder at once; tick 0 is the next tick */
    fake_encoder = 1234;
    send_start(SFLR_START_RESET_ENCODER, 0);
    CHECK(fake_encoder_resets == 2u);
    s = tick_sample();
    CHECK(s.u.sample.seq == 0 && s.u.sample.theta == 0 && s.u.sample.accel == 3); /* no offset now */
}

static void test_seq_wrap_and_restart(void)
{
    fresh(&sflr_default_config);
    send_start(0, 0);
    unsigned bad = 0;
    for (uint32_t k = 0; k < 70000u; k++) {
        sflr_msg_t s;
        sflr_tick(&dev);
        if (fake_take(&s, 1) != 1 || s.u.sample.seq != (uint16_t)k || (k > 0 && s.u.sample.status != 0) ||
            s.u.sample.v_applied != (k == 0 ? 0 : (int16_t)((k - 1u) % 200u))) {
            bad++;
        }
        send_command(s.u.sample.seq, (int16_t)(k % 200u));
    }
    CHECK(bad == 0); /* seq wraps 65535 -> 0 and commands keep matching */
    /* START during a run restarts it: tick 0 again, counters cleared */
    tick_sample();
    tick_sample(); /* one miss */
    send_start(0, 0);
    sflr_msg_t s = tick_sample();
    CHECK(s.u.sample.seq == 0 && s.u.sample.status == 0 && s.u.sample.v_applied == 0);
    CHECK(dev.late == 0);
}

/* START bit1's 16 averaging ticks: STOP, HELLO and COMMAND arriving meanwhile. */
static void test_during_zeroing(void)
{
    fresh(&sflr_default_config);
    sflr_msg_t m[4];
    send_start(SFLR_START_ZERO_ACCEL | SFLR_START_RESET_ENCODER, 0);
    CHECK(fake_amp && fake_dac == 0);
    for (int i = 0; i < 5; i++) {
        sflr_tick(&dev);
    }
    send_simple(SFLR_HELLO); /* answered at any time, also while averaging */
    CHECK(fake_take(m, 4) == 1 && m[0].type == SFLR_INFO);
    send_command(0, 99); /* nothing to answer yet: ignored, never applied */
    send_simple(SFLR_STOP);
    CHECK(fake_dac == 0 && !fake_amp); /* at once */
    CHECK(fake_take(m, 4) == 1 && m[0].type == SFLR_STOPPED && m[0].u.stopped.reason == SFLR_REASON_STOP &&
          m[0].u.stopped.ticks == 0u);
    for (int i = 0; i < 40; i++) {
        sflr_tick(&dev);
    }
    CHECK(fake_take(m, 4) == 0 && fake_dac == 0 && !fake_amp); /* no late tick 0, no reset */
    CHECK(fake_encoder_resets == 0u);

    /* a COMMAND while averaging does not leak into tick 0 or tick 1; it answers nothing: STALE */
    send_start(SFLR_START_ZERO_ACCEL, 0);
    for (int i = 0; i < 16; i++) {
        send_command(0, 77);
        sflr_tick(&dev);
    }
    CHECK(fake_take(m, 4) == 0);
    sflr_msg_t s = tick_sample();
    CHECK(s.u.sample.seq == 0 && s.u.sample.v_applied == 0 && s.u.sample.status == SFLR_ST_STALE);
    s = tick_sample();
    CHECK(s.u.sample.seq == 1 && s.u.sample.v_applied == 0 && s.u.sample.status == SFLR_ST_LATE);
}

/* START while the watchdog has the amplifier off: 0 V first, then enable; a clean run. */
static void test_restart_after_watchdog(void)
{
    sflr_config_t cfg = sflr_default_config;
    cfg.watchdog_ticks = 2;
    fresh(&cfg);
    send_start(0, 0);
    tick_sample();
    send_command(0, -120);
    CHECK(tick_sample().u.sample.v_applied == -120);
    tick_sample();
    sflr_msg_t s = tick_sample();
    CHECK((s.u.sample.status & SFLR_ST_WATCHDOG) && !fake_amp && fake_dac == 0);
    send_start(0, 3);
    CHECK(fake_amp && fake_dac == 0 && zero_before_last_enable() && fake_unsafe_enables == 0);
    s = tick_sample();
    CHECK(s.u.sample.seq == 0 && s.u.sample.status == 0 && s.u.sample.v_applied == 0);
    send_command(0, 30);
    s = tick_sample();
    CHECK(s.u.sample.v_applied == 30 && s.u.sample.status == 0);
    send_command(1, 31);
    sflr_msg_t m[3];
    sflr_tick(&dev); /* tick 2 = n_ticks - 1: SAMPLE 2 and STOPPED */
    CHECK(fake_take(m, 3) == 2 && m[1].type == SFLR_STOPPED && m[1].u.stopped.reason == SFLR_REASON_DONE);
    CHECK(m[1].u.stopped.ticks == 3u && m[1].u.stopped.late == 0u && m[1].u.stopped.watchdog_trips == 0u);
    CHECK(!fake_amp && fake_dac == 0);
}

int main(void)
{
    test_crc();
    test_cobs();
    test_valid_vectors();
    test_invalid_vectors();
    test_stream();
    test_overlong();
    test_reset_and_hello();
    test_start_tick0_and_delay();
    test_late_hold_and_watchdog(10);
    test_late_hold_and_watchdog(3);
    test_late_hold_and_watchdog(1);
    test_clamp();
    test_stale_and_rx_error();
    test_stop();
    test_n_ticks();
    test_zero_accel();
    test_seq_wrap_and_restart();
    test_during_zeroing();
    test_restart_after_watchdog();
    return t_finish();
}
