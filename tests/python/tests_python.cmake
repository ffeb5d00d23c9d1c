# The Python package's tests (client/python, docs/python.md): pytest with Debian's
# /usr/bin/python3 (the interpreter the module is built for), one ctest test per file, each in
# its own network namespace (deploy/netns-run.sh) like the C++ integration tests: the daemon
# tests' LCM multicast stays on that namespace's loopback. Labels: unit (arrays, no GL), gpu
# (far.Pipeline on llvmpipe), integration (far-daemon).
if(NOT TARGET far_python_client)
  return()
endif()
function(far_add_python_test file label)
  get_filename_component(name ${file} NAME_WE)
  add_test(NAME PythonTest.${name}
           COMMAND ${PROJECT_SOURCE_DIR}/deploy/netns-run.sh ${Python3_EXECUTABLE} -m pytest
                   -p no:cacheprovider -q -rs ${CMAKE_CURRENT_SOURCE_DIR}/python/${file})
  set_tests_properties(PythonTest.${name} PROPERTIES LABELS "${label};python" TIMEOUT 300
    ENVIRONMENT "PYTHONPATH=${PROJECT_BINARY_DIR}/python;PYTHONDONTWRITEBYTECODE=1;FAR_DAEMON_PATH=$<TARGET_FILE:far-daemon>;FAR_CLIENT_PATH=$<TARGET_FILE:far-client>;FAR_TEST_GPU_COST_CACHE=${PROJECT_BINARY_DIR}/tests/gpu-costs.json")
endfunction()
far_add_python_test(test_arrays.py unit)
far_add_python_test(test_pipeline.py gpu)
far_add_python_test(test_client.py integration)
far_add_python_test(test_threads.py integration)

# The python3-far .deb beside far's (deploy/debian/python3-far.cpack.in), unpacked into a
# scratch root and used from there with the packaged daemon. In a network namespace (LCM).
add_test(NAME PythonPackageTest.DebUnpacksBesideFarAndStepsAScene
         COMMAND ${PROJECT_SOURCE_DIR}/deploy/netns-run.sh
                 ${CMAKE_CURRENT_SOURCE_DIR}/python/package_test.sh ${PROJECT_BINARY_DIR}
                 ${PROJECT_SOURCE_DIR} ${PROJECT_VERSION})
set_tests_properties(PythonPackageTest.DebUnpacksBesideFarAndStepsAScene PROPERTIES
                     LABELS "integration;package;python" TIMEOUT 600)
