/* libnbt/error.c: status strings and the optional error handler. */
#include <config.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <nbt/nbt.h>
#include "internal.h"

static _Atomic(nbt_error_handler *) handler; /* static: starts as NULL (clang rejects "= NULL" for an _Atomic pointer) */

const char *nbt_strerror(nbt_status s)
{
    switch (s) {
    case NBT_OK: return "success";
    case NBT_EDOM: return "argument outside the domain";
    case NBT_ENOMEM: return "out of memory";
    case NBT_ETOL: return "tolerance not reached";
    case NBT_EIO: return "input/output error";
    case NBT_EFORMAT: return "bad format";
    case NBT_EINVAL: return "invalid arguments";
    }
    return "unknown status";
}

nbt_error_handler *nbt_set_error_handler(nbt_error_handler *h)
{
    return atomic_exchange(&handler, h);
}

nbt_status nbt__fail(nbt_status s, const char *reason)
{
    nbt_error_handler *h = atomic_load(&handler);
    if (h && s != NBT_OK && s != NBT_ETOL)
        h(reason, s);
    return s;
}

nbt_status nbt__failv(nbt_status s, const char *fmt, ...)
{
    char reason[320];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(reason, sizeof reason, fmt, ap);
    va_end(ap);
    return nbt__fail(s, reason);
}

const char *nbt_version(void)
{
    return PACKAGE_VERSION;
}
