# The far .deb (CPack, DEB generator): far-daemon with its systemd units, far-client, the client
# library with its headers and CMake package, the docs. From a built tree:
#   cpack --config build/release/CPackConfig.cmake -B <dir>    ->  <dir>/far_<version>_<arch>.deb
# docs/daemon.md ("Installing as a service") is the user's side; tests/package/ the test.

# The service files land in absolute system paths (/etc/far, /lib/systemd/system), so they form
# the component `service`, left out of a plain `cmake --install` (which must stay inside its
# --prefix); the package installs it by name (CPACK_INSTALL_CMAKE_PROJECTS below). Both units
# come from one file: far-daemon.service, and the template far-daemon@.service whose instance N
# is the daemon `gpuN` on EGL device N.
function(far_configure_unit file description exec_args)
  set(FAR_UNIT_NAME ${file})
  set(FAR_UNIT_HEADER "${file}: ${description}")
  set(FAR_UNIT_DESCRIPTION "${description}")
  set(FAR_UNIT_EXEC_ARGS "${exec_args}")
  configure_file(${PROJECT_SOURCE_DIR}/deploy/systemd/far-daemon.service.in
                 ${PROJECT_BINARY_DIR}/systemd/${file} @ONLY)
endfunction()
far_configure_unit(far-daemon.service "far collision-culling daemon" "")
far_configure_unit(far-daemon@.service "far collision-culling daemon gpu%i (EGL device %i)"
                   " --name gpu%i --gpu %i")
install(FILES ${PROJECT_BINARY_DIR}/systemd/far-daemon.service
              ${PROJECT_BINARY_DIR}/systemd/far-daemon@.service
        DESTINATION /lib/systemd/system COMPONENT service EXCLUDE_FROM_ALL)
install(FILES ${PROJECT_SOURCE_DIR}/deploy/debian/daemon.json
        DESTINATION /etc/far COMPONENT service EXCLUDE_FROM_ALL)
install(FILES ${PROJECT_SOURCE_DIR}/README.md ${PROJECT_SOURCE_DIR}/deploy/debian/copyright
        DESTINATION share/doc/far)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/ DESTINATION share/doc/far FILES_MATCHING PATTERN "*.md")

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME far)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_CONTACT "far maintainers <maintainers@users.noreply.h-seed-ea2a4ecd.example>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "GPU collision culling (FAR) as a service: far-daemon, far-client, far-snapshot, far::client")
set(CPACK_PACKAGE_DESCRIPTION
    "far-daemon serves simulators the potentially colliding set, exact contacts and distance \
pairs of their scenes, computed with Fast and Reliable Collision Culling on a headless OpenGL \
context (a GPU, else Mesa's llvmpipe). The package holds the daemon and its systemd units \
(far-daemon.service, far-daemon@.service), the far-client command line (no GL), far-snapshot \
(one step drawn to a PNG, in process), and the static client library with its headers and CMake \
package (find_package(far COMPONENTS client)).")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
# The prefix when CPACK_SET_DESTDIR is on (else CMAKE_INSTALL_PREFIX, /usr/local).
set(CPACK_INSTALL_PREFIX /usr)
# Absolute destinations (the service component) go under the package root, not the host's /.
set(CPACK_SET_DESTDIR ON)
set(CPACK_INSTALL_CMAKE_PROJECTS
    "${PROJECT_BINARY_DIR};far;Unspecified;/" "${PROJECT_BINARY_DIR};far;service;/")
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
# Linked libraries come from dpkg-shlibdeps (dpkg-dev). What is loaded at run time, which
# shlibdeps cannot see, is declared here (measured with LD_DEBUG=libs on a collide; the test
# installs the package on a minimal Debian 12 with these alone, tests/package/):
#  - libepoxy dlopens libEGL.so.1 (libegl1) and, for GL's core entry points, libGL.so.1 or
#    else libOpenGL.so.0 (libgl1 | libopengl0; without either it aborts: "Couldn't open
#    libGL.so.1 or libOpenGL.so.0"). libopengl0 first: it brings no GLX or X11;
#  - libglvnd's libEGL loads the vendor Mesa (libEGL_mesa.so.0: libegl-mesa0), which loads its
#    DRI driver (swrast_dri.so, llvmpipe, on a machine without a GPU; radeonsi, iris, nouveau
#    for AMD, Intel and NVIDIA's open driver: libgl1-mesa-dri).
# Depends, not Recommends: without Mesa's driver the daemon cannot make a context at all on
# a machine without a GPU (nor on an AMD or Intel one), and apt --no-install-recommends is the
# norm in containers. The cost: Mesa's drivers with LLVM (about 200 MB installed) also on a
# host with NVIDIA's driver, which brings its own EGL vendor. adduser runs in postinst.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_DEPENDS
    "adduser, libegl1, libopengl0 | libgl1, libegl-mesa0, libgl1-mesa-dri")
# What a find_package(far) user project needs (cmake/farConfig.cmake.in): the client component,
# then the core component's libraries.
set(CPACK_DEBIAN_PACKAGE_SUGGESTS
    "cmake, pkg-config, libeigen3-dev, libglib2.0-dev, libsodium-dev, libfcl-dev, libepoxy-dev, \
libpng-dev, nlohmann-json3-dev")
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
    ${PROJECT_SOURCE_DIR}/deploy/debian/postinst ${PROJECT_SOURCE_DIR}/deploy/debian/prerm
    ${PROJECT_SOURCE_DIR}/deploy/debian/postrm ${PROJECT_SOURCE_DIR}/deploy/debian/conffiles)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
include(CPack)
