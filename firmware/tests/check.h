/* check.h - tiny test bookkeeping shared by the host test programs. */
#ifndef SFLR_TEST_CHECK_H
#define SFLR_TEST_CHECK_H

#include <stdbool.h>
#include <stdio.h>

#include "sflr_proto.h"

/* Every CHECK counts; the closing line is "N passed, M failed". */
extern unsigned t_passed, t_failed;
#define CHECK(c) do { if (c) t_passed++; else { t_failed++; \
    printf("FAIL %s:%d: %s\n", __FILE__, __LINE__, #c); } } while (0)
/* Field-by-field equality of two messages of the same type. */
bool msg_eq(const sflr_msg_t *a, const sflr_msg_t *b);
/* Print the closing line; the exit status for main. */
int t_finish(void);

#endif
