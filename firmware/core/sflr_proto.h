/*
 * sflr_proto.h - protocol v1 wire format (spec/protocol.md): CRC-16/CCITT-FALSE,
 * COBS framing, message encode/decode and an incremental frame decoder.
 *
 * C99, no dynamic memory, no floating point. Every multi-byte field is packed
 * byte by byte little-endian (no struct casts), so the code is endian- and
 * alignment-independent.
 */
#ifndef SFLR_PROTO_H
#define SFLR_PROTO_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define SFLR_PROTOCOL_VERSION 1u

/* A whole frame on the wire, the 0x00 delimiter included, is at most 64 bytes. */
#define SFLR_FRAME_MAX 64u
/* Largest payload (INFO, type byte included) and its CRC. */
#define SFLR_PAYLOAD_MAX 20u
#define SFLR_CRC_LEN 2u

typedef enum {
    SFLR_SAMPLE = 0x01,
    SFLR_COMMAND = 0x02,
    SFLR_HELLO = 0x03,
    SFLR_INFO = 0x04,
    SFLR_START = 0x05,
    SFLR_STOP = 0x06,
    SFLR_STOPPED = 0x07
} sflr_type_t;

/* SAMPLE status bits */
#define SFLR_ST_LATE 0x01u
#define SFLR_ST_WATCHDOG 0x02u
#define SFLR_ST_SATURATED 0x04u
#define SFLR_ST_RX_ERROR 0x08u
#define SFLR_ST_STALE 0x10u

/* START flags */
#define SFLR_START_RESET_ENCODER 0x01u
#define SFLR_START_ZERO_ACCEL 0x02u

/* STOPPED reasons */
#define SFLR_REASON_STOP 0u
#define SFLR_REASON_DONE 1u

#define SFLR_NAME_LEN 8u

typedef struct {
    uint8_t type; /* sflr_type_t */
    union {
        struct { uint16_t seq; int32_t theta; int16_t accel; int16_t v_applied; uint8_t status; } sample;
        struct { uint16_t seq; int16_t v; } command;
        struct { uint8_t protocol_version; } hello;
        struct {
            uint8_t protocol_version, fw_major, fw_minor, fw_patch;
            uint16_t rate_hz;
            int16_t v_limit;
            uint16_t counts_per_rev;
            uint8_t watchdog_ticks;
            char name[SFLR_NAME_LEN]; /* ASCII, NUL-padded, not NUL-terminated */
        } info;
        struct { uint8_t flags; uint32_t n_ticks; } start;
        struct { uint8_t reason; uint32_t ticks; uint16_t late, watchdog_trips, rx_errors; } stopped;
    } u;
} sflr_msg_t;

/* Outcome of decoding one frame. Everything but OK and EMPTY is a receive error. */
typedef enum {
    SFLR_OK = 0,
    SFLR_PENDING,     /* decoder: byte stored, frame not complete yet */
    SFLR_EMPTY,       /* two 0x00 in a row: ignored, not counted */
    SFLR_ERR_COBS,    /* invalid COBS encoding */
    SFLR_ERR_SHORT,   /* decoded payload shorter than type + crc */
    SFLR_ERR_CRC,     /* crc mismatch */
    SFLR_ERR_TYPE,    /* unknown type byte */
    SFLR_ERR_LENGTH,  /* payload length wrong for its type */
    SFLR_ERR_OVERLONG /* more than SFLR_FRAME_MAX bytes before the delimiter */
} sflr_result_t;

static inline bool sflr_is_error(sflr_result_t r) { return r >= SFLR_ERR_COBS; }

uint16_t sflr_crc16(const uint8_t *data, size_t n);

/* COBS-encode n bytes into out (capacity cap). Returns the encoded length
 * (no delimiter) or 0 when cap is too small. */
size_t sflr_cobs_encode(const uint8_t *in, size_t n, uint8_t *out, size_t cap);
/* COBS-decode n bytes (no delimiter) into out (capacity cap). Returns the decoded
 * length, or -1 on invalid encoding (a zero byte, a code past the end) or overflow. */
int sflr_cobs_decode(const uint8_t *in, size_t n, uint8_t *out, size_t cap);

/* Payload length (type byte included) of a message type, 0 for an unknown type. */
size_t sflr_payload_len(uint8_t type);

/* Encode a message as a whole frame, 0x00 delimiter included. Returns the frame
 * length, or 0 for an unknown type or when cap is too small (cap >= SFLR_FRAME_MAX
 * always suffices). */
size_t sflr_encode(const sflr_msg_t *m, uint8_t *out, size_t cap);

/* Decode one frame's bytes between delimiters (delimiter excluded). */
sflr_result_t sflr_frame_decode(const uint8_t *raw, size_t n, sflr_msg_t *m);

/* Incremental decoder: feed bytes one at a time; never writes past its buffer. */
typedef struct {
    uint8_t raw[SFLR_FRAME_MAX - 1u]; /* frame bytes seen since the last 0x00 */
    uint8_t len;
    bool overlong; /* frame outgrew raw[]: drop it at the next 0x00 */
} sflr_decoder_t;

void sflr_decoder_init(sflr_decoder_t *d);
/* Returns SFLR_PENDING mid-frame; at a 0x00: SFLR_OK (*m filled), SFLR_EMPTY, or an error. */
sflr_result_t sflr_decoder_push(sflr_decoder_t *d, uint8_t byte, sflr_msg_t *m);

#endif
