"""The worker's environment: a run inside an MPI job or a Slurm allocation starts clean."""

from vibrofeed.engine.runner import clean_environment


def test_launcher_and_allocation_variables_are_removed_and_the_rest_kept():
    outer = {
        "PATH": "/usr/bin", "LD_LIBRARY_PATH": "/opt/lib", "HOME": "/root",
        "OMPI_COMM_WORLD_RANK": "3", "OMPI_COMM_WORLD_SIZE": "8", "PMIX_RANK": "3",
        "OPAL_PREFIX": "/usr", "ORTE_HNP": "x", "PRTE_MCA_x": "y", "HYDRA_PROXY": "z", "PMI_RANK": "3",
        "SLURM_JOB_ID": "42", "SLURM_NODELIST": "n[1-4]", "SLURM_STEP_ID": "0",
        "OMPI_ALLOW_RUN_AS_ROOT": "1",  # a launcher variable too: the worker's own mpirun gets a flag
        "MY_SLURM_NOTE": "kept",  # only prefixes count
    }
    env = clean_environment(outer)
    assert env == {"PATH": "/usr/bin", "LD_LIBRARY_PATH": "/opt/lib", "HOME": "/root",
                   "MY_SLURM_NOTE": "kept"}
    assert outer["SLURM_JOB_ID"] == "42", "the caller's mapping is not changed"
