/* Rig wiring options of the PSoC HAL, in one place for the HAL and its test.
 * Flip a sign here (or with -D in Build Settings) rather than rewiring; see README
 * "first power-up". */
#ifndef HAL_WIRING_H
#define HAL_WIRING_H

#ifndef ENCODER_SIGN
#define ENCODER_SIGN 1
#endif
#ifndef ACCEL_SIGN
#define ACCEL_SIGN 1
#endif
#ifndef AMP_EN_ACTIVE
#define AMP_EN_ACTIVE 1u /* level that enables the amplifier */
#endif

#endif
