/* sflr_proto.c - protocol v1 framing and messages; see sflr_proto.h. */
#include "sflr_proto.h"

#include <string.h>

uint16_t sflr_crc16(const uint8_t *data, size_t n)
{
    /* CRC-16/CCITT-FALSE: poly 0x1021, init 0xFFFF, MSB first, no xorout.
     * Bitwise: a 256-entry table costs 512 bytes of flash for ~20 bytes a tick. */
    uint16_t crc = 0xFFFFu;
    for (size_t i = 0; i < n; i++) {
        crc ^= (uint16_t)((uint16_t)data[i] << 8);
        for (int b = 0; b < 8; b++) {
            crc = (crc & 0x8000u) ? (uint16_t)((crc << 1) ^ 0x1021u) : (uint16_t)(crc << 1);
        }
    }
    return crc;
}

size_t sflr_cobs_encode(const uint8_t *in, size_t n, uint8_t *out, size_t cap)
{
    /* Worst case n + n/254 + 1 bytes. */
    if (cap < n + n / 254u + 1u) {
        return 0;
    }
    size_t code_at = 0; /* where the current block's code byte goes */
    size_t o = 1;
    uint8_t code = 1;
    for (size_t i = 0; i < n; i++) {
        if (in[i] == 0u) {
            out[code_at] = code;
            code_at = o++;
            code = 1;
        } else {
            out[o++] = in[i];
            code++;
            if (code == 0xFFu) { /* full block: no implied zero after it */
                out[code_at] = code;
                code_at = o++;
                code = 1;
            }
        }
    }
    out[code_at] = code;
    return o;
}

int sflr_cobs_decode(const uint8_t *in, size_t n, uint8_t *out, size_t cap)
{
    size_t i = 0, o = 0;
    while (i < n) {
        uint8_t code = in[i++];
        if (code == 0u || (size_t)(code - 1u) > n - i) {
            return -1; /* a zero inside a frame, or a block running past the end */
        }
        for (uint8_t k = 1; k < code; k++) {
            if (in[i] == 0u || o >= cap) {
                return -1;
            }
            out[o++] = in[i++];
        }
        if (code != 0xFFu && i < n) { /* implied zero between blocks */
            if (o >= cap) {
                return -1;
            }
            out[o++] = 0u;
        }
    }
    return (int)o;
}

size_t sflr_payload_len(uint8_t type)
{
    switch (type) {
    case SFLR_SAMPLE: return 12u;
    case SFLR_COMMAND: return 5u;
    case SFLR_HELLO: return 2u;
    case SFLR_INFO: return 20u;
    case SFLR_START: return 6u;
    case SFLR_STOP: return 1u;
    case SFLR_STOPPED: return 12u;
    default: return 0u;
    }
}

/* Little-endian packing, one byte at a time. Signed values go through their
 * unsigned two's-complement image (well defined in C99 conversions). */
static void put_u16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)(v & 0xFFu);
    p[1] = (uint8_t)(v >> 8);
}
static void put_u32(uint8_t *p, uint32_t v)
{
    for (int i = 0; i < 4; i++) {
        p[i] = (uint8_t)((v >> (8 * i)) & 0xFFu);
    }
}
static uint16_t get_u16(const uint8_t *p) { return (uint16_t)(p[0] | ((uint16_t)p[1] << 8)); }
static uint32_t get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}
/* Two's-complement reinterpretation without implementation-defined conversions. */
static int16_t to_i16(uint16_t u) { return u < 0x8000u ? (int16_t)u : (int16_t)((int32_t)u - 65536); }
static int32_t to_i32(uint32_t u)
{
    return u < 0x80000000u ? (int32_t)u : (int32_t)(u - 0x80000000u) - (int32_t)0x7FFFFFFF - 1;
}

/* Payload of m into p (SFLR_PAYLOAD_MAX bytes); returns its length, 0 if unknown type. */
static size_t pack(const sflr_msg_t *m, uint8_t *p)
{
    size_t n = sflr_payload_len(m->type);
    if (n == 0u) {
        return 0u;
    }
    p[0] = m->type;
    switch (m->type) {
    case SFLR_SAMPLE:
        put_u16(p + 1, m->u.sample.seq);
        put_u32(p + 3, (uint32_t)m->u.sample.theta);
        put_u16(p + 7, (uint16_t)m->u.sample.accel);
        put_u16(p + 9, (uint16_t)m->u.sample.v_applied);
        p[11] = m->u.sample.status;
        break;
    case SFLR_COMMAND:
        put_u16(p + 1, m->u.command.seq);
        put_u16(p + 3, (uint16_t)m->u.command.v);
        break;
    case SFLR_HELLO:
        p[1] = m->u.hello.protocol_version;
        break;
    case SFLR_INFO:
        p[1] = m->u.info.protocol_version;
        p[2] = m->u.info.fw_major;
        p[3] = m->u.info.fw_minor;
        p[4] = m->u.info.fw_patch;
        put_u16(p + 5, m->u.info.rate_hz);
        put_u16(p + 7, (uint16_t)m->u.info.v_limit);
        put_u16(p + 9, m->u.info.counts_per_rev);
        p[11] = m->u.info.watchdog_ticks;
        memcpy(p + 12, m->u.info.name, SFLR_NAME_LEN);
        break;
    case SFLR_START:
        p[1] = m->u.start.flags;
        put_u32(p + 2, m->u.start.n_ticks);
        break;
    case SFLR_STOP:
        break;
    case SFLR_STOPPED:
        p[1] = m->u.stopped.reason;
        put_u32(p + 2, m->u.stopped.ticks);
        put_u16(p + 6, m->u.stopped.late);
        put_u16(p + 8, m->u.stopped.watchdog_trips);
        put_u16(p + 10, m->u.stopped.rx_errors);
        break;
    default:
        return 0u;
    }
    return n;
}

static void unpack(const uint8_t *p, sflr_msg_t *m)
{
    memset(m, 0, sizeof *m);
    m->type = p[0];
    switch (p[0]) {
    case SFLR_SAMPLE:
        m->u.sample.seq = get_u16(p + 1);
        m->u.sample.theta = to_i32(get_u32(p + 3));
        m->u.sample.accel = to_i16(get_u16(p + 7));
        m->u.sample.v_applied = to_i16(get_u16(p + 9));
        m->u.sample.status = p[11];
        break;
    case SFLR_COMMAND:
        m->u.command.seq = get_u16(p + 1);
        m->u.command.v = to_i16(get_u16(p + 3));
        break;
    case SFLR_HELLO:
        m->u.hello.protocol_version = p[1];
        break;
    case SFLR_INFO:
        m->u.info.protocol_version = p[1];
        m->u.info.fw_major = p[2];
        m->u.info.fw_minor = p[3];
        m->u.info.fw_patch = p[4];
        m->u.info.rate_hz = get_u16(p + 5);
        m->u.info.v_limit = to_i16(get_u16(p + 7));
        m->u.info.counts_per_rev = get_u16(p + 9);
        m->u.info.watchdog_ticks = p[11];
        memcpy(m->u.info.name, p + 12, SFLR_NAME_LEN);
        break;
    case SFLR_START:
        m->u.start.flags = p[1];
        m->u.start.n_ticks = get_u32(p + 2);
        break;
    case SFLR_STOPPED:
        m->u.stopped.reason = p[1];
        m->u.stopped.ticks = get_u32(p + 2);
        m->u.stopped.late = get_u16(p + 6);
        m->u.stopped.watchdog_trips = get_u16(p + 8);
        m->u.stopped.rx_errors = get_u16(p + 10);
        break;
    default: /* STOP has no fields */
        break;
    }
}

size_t sflr_encode(const sflr_msg_t *m, uint8_t *out, size_t cap)
{
    uint8_t buf[SFLR_PAYLOAD_MAX + SFLR_CRC_LEN];
    size_t n = pack(m, buf);
    if (n == 0u) {
        return 0u;
    }
    uint16_t crc = sflr_crc16(buf, n);
    put_u16(buf + n, crc); /* crc appended little-endian */
    n += SFLR_CRC_LEN;
    if (cap < 1u) {
        return 0u;
    }
    size_t e = sflr_cobs_encode(buf, n, out, cap - 1u); /* keep room for the delimiter */
    if (e == 0u) {
        return 0u;
    }
    out[e] = 0u;
    return e + 1u;
}

sflr_result_t sflr_frame_decode(const uint8_t *raw, size_t n, sflr_msg_t *m)
{
    /* The spec's drop rules, in its order: COBS, length >= 3, CRC, type, length. */
    uint8_t buf[SFLR_FRAME_MAX];
    if (n == 0u) {
        return SFLR_EMPTY;
    }
    if (n > SFLR_FRAME_MAX - 1u) {
        return SFLR_ERR_OVERLONG;
    }
    int len = sflr_cobs_decode(raw, n, buf, sizeof buf);
    if (len < 0) {
        return SFLR_ERR_COBS;
    }
    if (len < 3) {
        return SFLR_ERR_SHORT;
    }
    size_t plen = (size_t)len - SFLR_CRC_LEN;
    if (sflr_crc16(buf, plen) != get_u16(buf + plen)) {
        return SFLR_ERR_CRC;
    }
    size_t want = sflr_payload_len(buf[0]);
    if (want == 0u) {
        return SFLR_ERR_TYPE;
    }
    if (plen != want) {
        return SFLR_ERR_LENGTH;
    }
    unpack(buf, m);
    return SFLR_OK;
}

void sflr_decoder_init(sflr_decoder_t *d)
{
    d->len = 0u;
    d->overlong = false;
}

sflr_result_t sflr_decoder_push(sflr_decoder_t *d, uint8_t byte, sflr_msg_t *m)
{
    if (byte != 0u) {
        if (d->len < sizeof d->raw) {
            d->raw[d->len++] = byte;
        } else {
            d->overlong = true; /* keep discarding until the next delimiter */
        }
        return SFLR_PENDING;
    }
    /* Delimiter: decode what we have and start afresh (resynchronisation point). */
    sflr_result_t r = d->overlong ? SFLR_ERR_OVERLONG : sflr_frame_decode(d->raw, d->len, m);
    sflr_decoder_init(d);
    return r;
}
