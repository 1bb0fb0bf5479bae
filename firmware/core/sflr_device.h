/*
 * sflr_device.h - the device side of protocol v1: tick logic, START/STOP/HELLO,
 * watchdog and amplifier-enable safety (spec/protocol.md).
 *
 * Concurrency: sflr_tick() and sflr_rx_bytes() must not run concurrently; a target
 * that ticks from an interrupt feeds received bytes with that interrupt masked
 * (PSoC: a critical section around sflr_rx_bytes; host: one mutex).
 */
#ifndef SFLR_DEVICE_H
#define SFLR_DEVICE_H

#include "sflr_proto.h"

#define SFLR_FW_MAJOR 1u
#define SFLR_FW_MINOR 0u
#define SFLR_FW_PATCH 0u
#define SFLR_ZERO_READINGS 16 /* accelerometer readings averaged by START bit1 */

typedef struct {
    uint16_t rate_hz;        /* tick rate, reported in INFO */
    int16_t v_limit;         /* output clamp, DAC counts */
    uint16_t counts_per_rev; /* encoder counts per base revolution */
    uint8_t watchdog_ticks;  /* consecutive misses that trip the watchdog (>= 1) */
    char name[SFLR_NAME_LEN];
} sflr_config_t;

/* The rig's defaults: 500 Hz, +-255 (the DAC's full range), 1024 counts/rev, 10 ticks. */
extern const sflr_config_t sflr_default_config;

typedef enum { SFLR_IDLE = 0, SFLR_ZEROING, SFLR_RUNNING } sflr_state_t;

typedef struct {
    sflr_config_t cfg;
    sflr_decoder_t rx;
    sflr_state_t state;
    /* run parameters */
    uint32_t n_ticks;      /* 0 = until STOP */
    bool reset_encoder;    /* START bit0, applied just before tick 0 */
    /* tick bookkeeping */
    uint32_t k;            /* index of the next tick */
    int16_t out;           /* output applied during the last tick (held when LATE) */
    bool amp_on;
    uint16_t misses;       /* consecutive ticks without the expected COMMAND */
    bool watchdog;
    /* mailbox: the COMMAND answering the last SAMPLE sent */
    bool expect_valid;     /* a SAMPLE has been sent this run */
    uint16_t expect_seq;   /* seq of that SAMPLE */
    bool cmd_ready;
    int16_t cmd_v;
    /* flags reported in the next SAMPLE */
    bool rx_error_flag, stale_flag;
    /* accelerometer zeroing */
    int32_t accel_sum;
    uint8_t accel_n;
    int16_t accel_offset;
    /* counters reported in STOPPED (saturating) */
    uint16_t late, watchdog_trips, rx_errors;
} sflr_dev_t;

/* Reset state: amplifier disabled, DAC at 0 V, idle. */
void sflr_init(sflr_dev_t *d, const sflr_config_t *cfg);
/* Feed received bytes; handles every complete frame. */
void sflr_rx_bytes(sflr_dev_t *d, const uint8_t *data, size_t n);
/* One timer tick (call at cfg.rate_hz). Integer only: safe in an interrupt. */
void sflr_tick(sflr_dev_t *d);

#endif
