/* fake_hal.h - a recording HAL for the host unit tests, and tiny test helpers. */
#ifndef FAKE_HAL_H
#define FAKE_HAL_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "check.h"
#include "sflr_device.h"

extern int32_t fake_encoder;      /* what hal_encoder_read returns */
extern int16_t fake_accel;        /* what hal_accel_read returns */
extern int16_t fake_dac;          /* last hal_dac_write value */
extern bool fake_amp;             /* last hal_amp_enable value */
extern unsigned fake_encoder_resets;
extern unsigned fake_unsafe_enables; /* enable went active while the DAC was not at 0 V */
extern int fake_events[64];       /* last hardware writes: dac value, or AMP_ON/AMP_OFF */
extern unsigned fake_n_events;
#define FAKE_AMP_ON 100000
#define FAKE_AMP_OFF (-100000)

void fake_reset(void);
/* Decode everything the device sent since the last call; returns how many messages. */
int fake_take(sflr_msg_t *out, int max);


#endif
