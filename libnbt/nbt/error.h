/* nbt/error.h: status codes returned by every fallible libnbt call. */
#ifndef NBT_ERROR_H
#define NBT_ERROR_H

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    NBT_OK = 0,
    NBT_EDOM,      /* an argument is outside the domain of the function */
    NBT_ENOMEM,    /* allocation failed */
    NBT_ETOL,      /* requested tolerance not reached; result and error estimate still set */
    NBT_EIO,       /* a file could not be opened, read or written */
    NBT_EFORMAT,   /* a file or string is not in the expected format */
    NBT_EINVAL     /* an invalid combination of arguments */
} nbt_status;

/* A fixed English description of a status code. Never NULL. */
const char *nbt_strerror(nbt_status status);

/* Optional error handler, called (if set) with a reason each time libnbt
 * returns a status other than NBT_OK/NBT_ETOL. The default is none. The
 * handler must be thread-safe if libnbt is used from several threads.
 * Returns the previous handler. */
typedef void nbt_error_handler(const char *reason, nbt_status status);
nbt_error_handler *nbt_set_error_handler(nbt_error_handler *handler);

#ifdef __cplusplus
}
#endif
#endif
