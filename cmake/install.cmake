# `cmake --install build --prefix P`: the `cullide` command, the static libraries and their public
# headers, share/cullide/ (data/ and tools/ as in the source tree: the installed command finds them
# beside itself, core's resources.h), a CMake package (find_package(cullide 0.3) gives cullide::core,
# cullide::raster, cullide::raster_verify, cullide::oracle, cullide::peers, cullide::pipeline, cullide::study) and a
# pkg-config file.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(CULLIDE_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/cullide)
install(TARGETS cullide_core cullide_raster cullide_raster_verify cullide_oracle cullide_peers cullide_pipeline cullide_study
        EXPORT cullideTargets ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS cullide RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY core/include/ raster/include/ raster/verify/include/ oracle/include/ peers/include/ tools/pipeline/include/
                  tools/study/include/
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY data/ DESTINATION ${CMAKE_INSTALL_DATADIR}/cullide/data)
install(PROGRAMS tools/plot.py DESTINATION ${CMAKE_INSTALL_DATADIR}/cullide/tools)
install(DIRECTORY tools/plotting DESTINATION ${CMAKE_INSTALL_DATADIR}/cullide/tools  # the package plot.py runs
        FILES_MATCHING PATTERN "*.py" PATTERN "__pycache__" EXCLUDE)
install(PROGRAMS tools/trace/replay_reference.py DESTINATION ${CMAKE_INSTALL_DATADIR}/cullide/tools/trace)
# The report's 3D view (plotting/view3d.py): its module, and the three.js files it inlines where
# tools/setup.sh installed them (npm ci in tools/report3d).
set(CULLIDE_THREE tools/report3d/node_modules/three)
install(FILES tools/report3d/view.js tools/report3d/package.json tools/report3d/package-lock.json
        DESTINATION ${CMAKE_INSTALL_DATADIR}/cullide/tools/report3d)
install(FILES ${CULLIDE_THREE}/build/three.module.min.js ${CULLIDE_THREE}/build/three.core.min.js
        DESTINATION ${CMAKE_INSTALL_DATADIR}/cullide/${CULLIDE_THREE}/build OPTIONAL)
install(FILES ${CULLIDE_THREE}/LICENSE DESTINATION ${CMAKE_INSTALL_DATADIR}/cullide/${CULLIDE_THREE} OPTIONAL)
install(FILES ${CULLIDE_THREE}/examples/jsm/controls/OrbitControls.js
        DESTINATION ${CMAKE_INSTALL_DATADIR}/cullide/${CULLIDE_THREE}/examples/jsm/controls OPTIONAL)
install(FILES LICENSE README.md CHANGELOG.md CITATION.cff DESTINATION ${CMAKE_INSTALL_DOCDIR})

install(EXPORT cullideTargets NAMESPACE cullide:: DESTINATION ${CULLIDE_CMAKE_DIR})
configure_package_config_file(cmake/cullideConfig.cmake.in ${PROJECT_BINARY_DIR}/cullideConfig.cmake
                              INSTALL_DESTINATION ${CULLIDE_CMAKE_DIR}
                              PATH_VARS CMAKE_INSTALL_DATADIR)
# 0.3 accepts 0.3.x: the API may still change between minor versions before 1.0.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/cullideConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/cullideConfig.cmake ${PROJECT_BINARY_DIR}/cullideConfigVersion.cmake
        DESTINATION ${CULLIDE_CMAKE_DIR})

# pkg-config: the libraries are static, so everything they need is in Libs (not Libs.private,
# which plain `pkg-config --libs` leaves out).
if(CULLIDE_GL)
  set(CULLIDE_PC_GL_LIBS "-lepoxy -l${CMAKE_DL_LIBS}")
endif()
if(CULLIDE_VULKAN)
  string(APPEND CULLIDE_PC_GL_LIBS " -lvulkan")  # the Vulkan backend links the loader
endif()
# The .pc file is relocatable (prefix from pkg-config's ${pcfiledir}), as `--install --prefix` may differ
# from CMAKE_INSTALL_PREFIX.
file(RELATIVE_PATH CULLIDE_PC_PREFIX /P/${CMAKE_INSTALL_LIBDIR}/pkgconfig /P)
configure_file(cmake/cullide.pc.in ${PROJECT_BINARY_DIR}/cullide.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/cullide.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
