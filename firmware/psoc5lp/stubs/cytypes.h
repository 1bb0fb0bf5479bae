/* Stub of PSoC Creator's cytypes.h: only what firmware/psoc5lp uses, same names and
 * types as the generated file, for the host-side target compile check. Not for linking. */
#ifndef CY_TYPES_H
#define CY_TYPES_H

typedef unsigned char uint8;
typedef unsigned short uint16;
typedef unsigned long uint32;
typedef signed char int8;
typedef signed short int16;
typedef signed long int32;

typedef void (*cyisraddress)(void);
#define CY_ISR(FuncName) void FuncName(void)
#define CY_ISR_PROTO(FuncName) void FuncName(void)

#endif
