/* test_fuzz.c - seeded randomized test of the decoder and the device.
 *
 * gcc-only stand-in for libFuzzer: >= 10^6 random frames (valid, mutated) and
 * arbitrary byte streams, run under ASan/UBSan, with properties checked:
 * valid frames round-trip, nothing decodes that would not re-encode to itself,
 * and the device keeps its safety invariants whatever it is fed.
 * Usage: test_fuzz [seed] [frames]
 */
#include <stdlib.h>
#include <string.h>

#include "fake_hal.h"
#include "sflr_device.h"
#include "sflr_proto.h"

static uint64_t rng_state;

static uint64_t rnd(void) /* splitmix64: tiny, seedable, good enough */
{
    uint64_t z = (rng_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}
static uint32_t rnd_below(uint32_t n) { return (uint32_t)(rnd() % n); }

static void random_msg(sflr_msg_t *m)
{
    memset(m, 0, sizeof *m);
    m->type = (uint8_t)(1u + rnd_below(7));
    uint64_t r = rnd(), q = rnd();
    switch (m->type) {
    case SFLR_SAMPLE:
        m->u.sample.seq = (uint16_t)r;
        m->u.sample.theta = (int32_t)(uint32_t)(r >> 16); /* gcc: modulo conversion */
        m->u.sample.accel = (int16_t)(uint16_t)q;
        m->u.sample.v_applied = (int16_t)(uint16_t)(q >> 16);
        m->u.sample.status = (uint8_t)(q >> 32);
        break;
    case SFLR_COMMAND:
        m->u.command.seq = (uint16_t)r;
        m->u.command.v = (int16_t)(uint16_t)(r >> 16);
        break;
    case SFLR_HELLO: m->u.hello.protocol_version = (uint8_t)r; break;
    case SFLR_INFO:
        m->u.info.protocol_version = (uint8_t)r;
        m->u.info.fw_major = (uint8_t)(r >> 8);
        m->u.info.rate_hz = (uint16_t)(r >> 16);
        m->u.info.v_limit = (int16_t)(uint16_t)(r >> 32);
        m->u.info.counts_per_rev = (uint16_t)(r >> 48);
        m->u.info.watchdog_ticks = (uint8_t)q;
        for (int i = 0; i < 8; i++) {
            m->u.info.name[i] = (char)(0x20 + ((q >> (8 + i * 7)) & 0x3F));
        }
        break;
    case SFLR_START:
        m->u.start.flags = (uint8_t)r;
        m->u.start.n_ticks = (uint32_t)(r >> 8);
        break;
    case SFLR_STOPPED:
        m->u.stopped.reason = (uint8_t)r;
        m->u.stopped.ticks = (uint32_t)(r >> 8);
        m->u.stopped.late = (uint16_t)q;
        m->u.stopped.watchdog_trips = (uint16_t)(q >> 16);
        m->u.stopped.rx_errors = (uint16_t)(q >> 32);
        break;
    default: break;
    }
}

/* Mutate an encoded frame (delimiter excluded) in place; returns its new length. */
static size_t mutate(uint8_t *f, size_t n, size_t cap)
{
    switch (rnd_below(4)) {
    case 0: f[rnd_below((uint32_t)n)] ^= (uint8_t)(1u << rnd_below(8)); break; /* bit flip */
    case 1: f[rnd_below((uint32_t)n)] = (uint8_t)rnd(); break;                  /* byte change */
    case 2: if (n > 1) { size_t i = rnd_below((uint32_t)n); memmove(f + i, f + i + 1, n - i - 1); n--; } break;
    default: if (n < cap) { size_t i = rnd_below((uint32_t)n + 1u); memmove(f + i + 1, f + i, n - i); f[i] = (uint8_t)rnd(); n++; } break;
    }
    return n;
}

/* Whatever decodes must be a message that encodes back to the same bytes. */
static bool consistent(const uint8_t *raw, size_t n, const sflr_msg_t *m)
{
    uint8_t again[SFLR_FRAME_MAX];
    size_t e = sflr_encode(m, again, sizeof again);
    return e == n + 1u && memcmp(again, raw, n) == 0;
}

int main(int argc, char **argv)
{
    uint64_t seed = argc > 1 ? strtoull(argv[1], NULL, 0) : 20261121u;
    unsigned long frames = argc > 2 ? strtoul(argv[2], NULL, 0) : 1000000ul;
    rng_state = seed;
    printf("fuzz: seed %llu, %lu frames\n", (unsigned long long)seed, frames);

    unsigned long roundtrip_bad = 0, mutated_ok = 0, inconsistent = 0, nonterminal = 0;
    sflr_decoder_t d;
    sflr_decoder_init(&d);
    for (unsigned long i = 0; i < frames; i++) {
        sflr_msg_t m, got;
        uint8_t f[SFLR_FRAME_MAX + 8];
        random_msg(&m);
        size_t n = sflr_encode(&m, f, SFLR_FRAME_MAX) - 1u; /* body without delimiter */
        bool mutated = rnd_below(2) == 0;
        if (mutated) {
            n = mutate(f, n, SFLR_FRAME_MAX + 7u);
        }
        /* feed body + delimiter through the incremental decoder */
        sflr_result_t r = SFLR_PENDING;
        for (size_t k = 0; k < n; k++) {
            r = sflr_decoder_push(&d, f[k], &got);
            if (f[k] != 0u && r != SFLR_PENDING) {
                nonterminal++; /* only a delimiter may end a frame */
            }
        }
        if (memchr(f, 0, n) == NULL) {
            r = sflr_decoder_push(&d, 0u, &got);
            if (!mutated && (r != SFLR_OK || !msg_eq(&got, &m))) {
                roundtrip_bad++;
            }
            if (r == SFLR_OK && !consistent(f, n, &got)) {
                inconsistent++;
            }
            mutated_ok += mutated && r == SFLR_OK && !msg_eq(&got, &m);
        } else {
            sflr_decoder_push(&d, 0u, &got);
        }
    }
    CHECK(roundtrip_bad == 0);
    CHECK(inconsistent == 0);
    CHECK(nonterminal == 0);
    printf("fuzz: %lu mutated frames still decoded (to a different, self-consistent message)\n", mutated_ok);

    /* Arbitrary byte streams, 0x00 roughly every 32 bytes, some longer than a frame. */
    unsigned long stream_inconsistent = 0;
    for (unsigned long i = 0; i < frames; i++) {
        uint8_t buf[96];
        size_t n = rnd_below(sizeof buf);
        for (size_t k = 0; k < n; k++) {
            buf[k] = rnd_below(32) == 0 ? 0u : (uint8_t)rnd();
        }
        for (size_t k = 0; k < n; k++) {
            sflr_msg_t got;
            (void)sflr_decoder_push(&d, buf[k], &got); /* ASan/UBSan judge this part */
        }
        /* one-shot decode of the same bytes up to the first zero, checked for consistency */
        size_t body = n;
        const uint8_t *z = memchr(buf, 0, n);
        if (z != NULL) {
            body = (size_t)(z - buf);
        }
        sflr_msg_t got;
        if (sflr_frame_decode(buf, body, &got) == SFLR_OK && !consistent(buf, body, &got)) {
            stream_inconsistent++;
        }
    }
    CHECK(stream_inconsistent == 0);
    CHECK(d.len <= sizeof d.raw);

    /* The device under random input and ticks: safety invariants must always hold. */
    fake_reset();
    sflr_dev_t dev;
    sflr_config_t cfg = sflr_default_config;
    cfg.v_limit = 200;
    sflr_init(&dev, &cfg);
    unsigned long bad_sample = 0, unsafe = 0;
    for (unsigned long i = 0; i < frames / 4u; i++) {
        uint8_t buf[SFLR_FRAME_MAX + 8];
        size_t n;
        uint32_t what = rnd_below(8);
        if (what < 5) { /* a valid message, mostly COMMANDs near the expected seq */
            sflr_msg_t m;
            random_msg(&m);
            if (what < 3) {
                m.type = SFLR_COMMAND;
                m.u.command.seq = (uint16_t)(dev.expect_seq + rnd_below(3) - 1u);
            } else if (m.type == SFLR_START) {
                m.u.start.n_ticks %= 2000u;
            }
            n = sflr_encode(&m, buf, SFLR_FRAME_MAX);
        } else {
            n = rnd_below(sizeof buf);
            for (size_t k = 0; k < n; k++) {
                buf[k] = rnd_below(16) == 0 ? 0u : (uint8_t)rnd();
            }
        }
        sflr_rx_bytes(&dev, buf, n);
        fake_accel = (int16_t)(uint16_t)rnd();
        fake_encoder = (int32_t)(uint32_t)rnd();
        sflr_tick(&dev);
        sflr_msg_t out[8];
        int got = fake_take(out, 8);
        for (int k = 0; k < got; k++) {
            if (out[k].type != SFLR_SAMPLE) {
                continue;
            }
            const int v = out[k].u.sample.v_applied;
            const uint8_t st = out[k].u.sample.status;
            /* the DAC still holds v unless n_ticks ended the run in this tick (output 0 since) */
            if (v > cfg.v_limit || v < -cfg.v_limit || (dev.state != SFLR_IDLE && v != fake_dac) ||
                ((st & SFLR_ST_WATCHDOG) && (v != 0 || fake_amp))) {
                bad_sample++;
            }
        }
        if (dev.state == SFLR_IDLE && (fake_amp || fake_dac != 0)) {
            unsafe++; /* after STOP / n_ticks / reset: output 0, amplifier off */
        }
    }
    CHECK(bad_sample == 0);
    CHECK(unsafe == 0);
    CHECK(fake_unsafe_enables == 0);
    return t_finish();
}
