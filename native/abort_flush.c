/* Flush every stdio stream before MPI_Abort.
 *
 * LIGGGHTS' error->one() prints "ERROR on proc N: ..." to its (buffered)
 * screen file and calls MPI_Abort, which ends the process without flushing:
 * the message is lost. vibrofeed preloads this library into its engine
 * workers (LD_PRELOAD), so the message reaches the file and can be reported.
 * Uses the MPI profiling interface: the real abort is PMPI_Abort.
 */
#include <mpi.h>
#include <stdio.h>

int MPI_Abort(MPI_Comm comm, int errorcode)
{
    fflush(NULL);
    return PMPI_Abort(comm, errorcode);
}
