# Slurm (docs/cluster.md, "Slurm"): a one-node cluster of the test's own (munged, slurmctld,
# slurmd, every file in a temporary directory) runs deploy/slurm/far-job.sbatch with this
# tree's far-daemon and far-client: several tasks' contacts against far-snapshot's, and a job
# cancelled mid-step that must leave no far process and no segment. Slurm's TCP and far's LCM on
# a private loopback (deploy/netns-run.sh). About 20-40 s on 2 cores. Skipped (77, saying why)
# where slurm-wlm or munge is not installed.
if(TARGET far-daemon AND TARGET far-client AND TARGET far-snapshot)
  add_test(NAME SlurmTest.OneNodeClusterRunsFarJobsAndACancelledJobLeavesNothing
           COMMAND ${PROJECT_SOURCE_DIR}/deploy/netns-run.sh
                   ${CMAKE_CURRENT_SOURCE_DIR}/slurm/slurm_cluster_test.sh ${PROJECT_BINARY_DIR}
                   ${PROJECT_SOURCE_DIR})
  set_tests_properties(SlurmTest.OneNodeClusterRunsFarJobsAndACancelledJobLeavesNothing PROPERTIES
                       LABELS "integration;slurm" SKIP_RETURN_CODE 77 TIMEOUT 600)
endif()
