/* gen/outputs.h: the files nbt-gen writes, registered so that a run that is
 * interrupted (SIGINT, SIGTERM, SIGHUP) or fails leaves nothing behind: no
 * PATH.tmpPID temporaries and none of the set's files written so far (the
 * man page promises all or nothing). */
#ifndef NBT_GEN_OUTPUTS_H
#define NBT_GEN_OUTPUTS_H

typedef struct outputs_file outputs_file;

/* Install the signal handlers and an exit hook that removes whatever is not
 * committed (die() and a non-zero return from main alike). */
void outputs_install(void);
/* Register PATH (its temporary is PATH.tmpPID, the writers' convention);
 * NULL when out of memory. Nothing is removed for it until outputs_begin. */
outputs_file *outputs_add(const char *path);
/* PATH is about to be written (it replaces any older file of that name);
 * non-zero when a signal already arrived: do not start. Every zero return
 * is followed by outputs_end (from the same thread): a signal waits up to
 * 2 s for the writes in flight before it removes the files. */
int outputs_begin(outputs_file *f);
/* The write ended: ok (renamed into place) or failed (only its temporary
 * may be left; an older file of that name is not ours to remove). */
void outputs_end(outputs_file *f, int ok);
/* A directory this run created: removed (if empty) after its files. */
void outputs_dir(const char *dir);
/* Success: keep everything registered so far. */
void outputs_commit(void);
/* Failure: remove everything registered and not committed. */
void outputs_abort(void);

#endif
