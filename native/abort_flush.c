/* Flush before MPI_Abort.
 *
 * LIGGGHTS' error->one() prints "ERROR on proc N: ..." to its (buffered)
 * screen file and calls MPI_Abort, which ends the process without flushing:
 * the message is lost, and so are frames vibrofeed has computed but not yet
 * written. vibrofeed preloads this library into its engine workers
 * (LD_PRELOAD): MPI_Abort then calls the hook the worker registered (which
 * writes its pending frames), flushes every stdio stream, and aborts through
 * the MPI profiling interface (PMPI_Abort).
 */
#include <mpi.h>
#include <stdio.h>

static void (*abort_hook)(void) = 0;

void vibrofeed_set_abort_hook(void (*hook)(void))
{
    abort_hook = hook;
}

int MPI_Abort(MPI_Comm comm, int errorcode)
{
    if (abort_hook) {
        void (*hook)(void) = abort_hook;
        abort_hook = 0; /* once, even if the hook itself aborts */
        hook();
    }
    fflush(NULL);
    return PMPI_Abort(comm, errorcode);
}
