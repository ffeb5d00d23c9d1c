# The Kubernetes manifests (deploy/kubernetes/, docs/cluster.md), checked offline: against the
# Kubernetes API's schema (the swagger.json of Debian 12's kubernetes source package, fetched
# through apt on the first run into .deps/kubernetes/: about 5 s, then cached; 1-3 s after), and against
# the far-daemon built here. Skipped (77) only when apt reaches no archive for the schema.
add_test(NAME KubernetesTest.ManifestsValidateAgainstTheApiSchema
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/kubernetes/manifests_test.sh ${PROJECT_SOURCE_DIR}
                 ${PROJECT_VERSION})
set_tests_properties(KubernetesTest.ManifestsValidateAgainstTheApiSchema PROPERTIES
                     LABELS "unit;kubernetes" SKIP_RETURN_CODE 77 TIMEOUT 300)
add_test(NAME KubernetesTest.DaemonAcceptsTheDaemonSetsFlagsAndConfigMap
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/kubernetes/daemon_flags_test.sh
                 $<TARGET_FILE:far-daemon> ${PROJECT_SOURCE_DIR})
set_tests_properties(KubernetesTest.DaemonAcceptsTheDaemonSetsFlagsAndConfigMap PROPERTIES
                     LABELS "unit;kubernetes" TIMEOUT 60)
