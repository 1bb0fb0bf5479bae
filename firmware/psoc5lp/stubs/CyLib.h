/* Stub of PSoC Creator's CyLib.h (subset). */
#ifndef CY_BOOT_CYLIB_H
#define CY_BOOT_CYLIB_H

#include "cytypes.h"

#define CyGlobalIntEnable do { __asm("CPSIE   i"); } while (0)
#define CyGlobalIntDisable do { __asm("CPSID   i"); } while (0)

#define CYWDT_2_TICKS (0x0u)    /*    4 -    6 ms */
#define CYWDT_16_TICKS (0x1u)   /*   32 -   48 ms */
#define CYWDT_128_TICKS (0x2u)  /*  256 -  384 ms */
#define CYWDT_1024_TICKS (0x3u) /* 2048 - 3072 ms */
#define CYWDT_LPMODE_NOCHANGE (0x00u)

void CyILO_Start1K(void);
void CyWdtStart(uint8 ticks, uint8 lpMode);
void CyWdtClear(void);

uint8 CyEnterCriticalSection(void);
void CyExitCriticalSection(uint8 savedIntrStatus);

#endif
