/*
 * sflr_hal.h - the only way the core touches hardware. Each target (PSoC 5LP,
 * the host firmware-in-the-loop build, the unit tests) links one implementation.
 * All functions are called from the tick (interrupt) context or from wherever the
 * target feeds received bytes; they must not block.
 */
#ifndef SFLR_HAL_H
#define SFLR_HAL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* Encoder position in counts (1024 per base revolution), as a free-running signed count. */
int32_t hal_encoder_read(void);
/* Zero the encoder count. */
void hal_encoder_reset(void);
/* Latest accelerometer reading in raw signed ADC counts (no waiting). */
int16_t hal_accel_read(void);
/* Drive the motor amplifier input: v in DAC counts, 0 = 0 V, +-255 = +-2.5 V. */
void hal_dac_write(int16_t v);
/* Amplifier enable output: true = amplifier may drive the motor. */
void hal_amp_enable(bool on);
/* Queue n bytes for transmission; must not block (drop when the queue is full). */
void hal_uart_write(const uint8_t *data, size_t n);

#endif
