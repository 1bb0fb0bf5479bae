/* Stub of the project.h PSoC Creator generates: includes every placed component's API.
 * Only for `make target-check` (compile, no link); the real build uses the generated one. */
#ifndef CY_PROJECT_H
#define CY_PROJECT_H

#include "cytypes.h"
#include "CyLib.h"
#include "ADC.h"
#include "AMP_EN.h"
#include "BUF_N.h"
#include "BUF_P.h"
#include "Clock_tick.h"
#include "DAC_N.h"
#include "DAC_P.h"
#include "QuadDec.h"
#include "USBUART.h"
#include "isr_tick.h"

#endif
