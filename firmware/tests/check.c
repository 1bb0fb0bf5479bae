/* check.c - see check.h */
#include "check.h"

#include <string.h>

unsigned t_passed, t_failed;

bool msg_eq(const sflr_msg_t *a, const sflr_msg_t *b)
{
    if (a->type != b->type) {
        return false;
    }
    switch (a->type) {
    case SFLR_SAMPLE:
        return a->u.sample.seq == b->u.sample.seq && a->u.sample.theta == b->u.sample.theta &&
               a->u.sample.accel == b->u.sample.accel && a->u.sample.v_applied == b->u.sample.v_applied &&
               a->u.sample.status == b->u.sample.status;
    case SFLR_COMMAND:
        return a->u.command.seq == b->u.command.seq && a->u.command.v == b->u.command.v;
    case SFLR_HELLO:
        return a->u.hello.protocol_version == b->u.hello.protocol_version;
    case SFLR_INFO:
        return a->u.info.protocol_version == b->u.info.protocol_version &&
               a->u.info.fw_major == b->u.info.fw_major && a->u.info.fw_minor == b->u.info.fw_minor &&
               a->u.info.fw_patch == b->u.info.fw_patch && a->u.info.rate_hz == b->u.info.rate_hz &&
               a->u.info.v_limit == b->u.info.v_limit && a->u.info.counts_per_rev == b->u.info.counts_per_rev &&
               a->u.info.watchdog_ticks == b->u.info.watchdog_ticks &&
               memcmp(a->u.info.name, b->u.info.name, SFLR_NAME_LEN) == 0;
    case SFLR_START:
        return a->u.start.flags == b->u.start.flags && a->u.start.n_ticks == b->u.start.n_ticks;
    case SFLR_STOP:
        return true;
    case SFLR_STOPPED:
        return a->u.stopped.reason == b->u.stopped.reason && a->u.stopped.ticks == b->u.stopped.ticks &&
               a->u.stopped.late == b->u.stopped.late && a->u.stopped.watchdog_trips == b->u.stopped.watchdog_trips &&
               a->u.stopped.rx_errors == b->u.stopped.rx_errors;
    default:
        return false;
    }
}

int t_finish(void)
{
    printf("%u passed, %u failed\n", t_passed, t_failed);
    return t_failed == 0u ? 0 : 1;
}
