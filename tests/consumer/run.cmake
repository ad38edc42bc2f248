# The install test (CTest Package.InstallConsumer): installs the build into a temporary prefix, then
#   1. builds tests/consumer/ against it with find_package(cullide 0.3) and runs it on the installed cow;
#   2. runs the installed `cullide`: --version is the package's version; make-scene reads the
#      installed share/cullide/data, and with that mesh removed fails naming the prefix (so the
#      installed command never falls back to the source tree); plot finds the installed plot.py;
#   3. pkg-config --cflags --libs cullide points into the prefix;
#   4. with PYTHON set (the module was built): `import cullide` from the installed package, whose
#      data folder is the prefix's.
# cmake -DBUILD_DIR=... -DSOURCE_DIR=... -DWORK_DIR=... -DVERSION=... [-DPYTHON=...] -P run.cmake
foreach(v BUILD_DIR SOURCE_DIR WORK_DIR VERSION)
  if(NOT ${v})
    message(FATAL_ERROR "run.cmake: -D${v}=... is required")
  endif()
endforeach()

function(run)  # run(<command...>) fails the test on a non-zero exit, showing the output
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  set(last_output "${out}${err}" PARENT_SCOPE)
endfunction()

set(prefix ${WORK_DIR}/prefix)
file(REMOVE_RECURSE ${WORK_DIR})
run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})

# 1. The consumer project.
run(${CMAKE_COMMAND} -S ${SOURCE_DIR}/tests/consumer -B ${WORK_DIR}/consumer -DCMAKE_BUILD_TYPE=Release
    -DCMAKE_PREFIX_PATH=${prefix})
run(${CMAKE_COMMAND} --build ${WORK_DIR}/consumer)
run(${WORK_DIR}/consumer/consumer ${prefix}/share/cullide/data/meshes/cow.off ${VERSION})
message(STATUS "${last_output}")

# 2. The installed command.
run(${prefix}/bin/cullide --version)
if(NOT last_output MATCHES "${VERSION}")
  message(FATAL_ERROR "installed cullide --version says '${last_output}', the package is ${VERSION}")
endif()
run(${prefix}/bin/cullide make-scene cows --triangles 500 -o ${WORK_DIR}/cows.json)
file(REMOVE ${prefix}/share/cullide/data/meshes/cow.off)
execute_process(COMMAND ${prefix}/bin/cullide make-scene cows --triangles 500 -o ${WORK_DIR}/cows2.json
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc EQUAL 0 OR NOT err MATCHES "${prefix}/share/cullide/data/meshes/cow.off")
  message(FATAL_ERROR "without the installed cow.off, make-scene should fail naming it (exit ${rc}): ${out}${err}")
endif()

# The installed plot script is found (the command checks for it before its inputs).
execute_process(COMMAND ${prefix}/bin/cullide plot ${WORK_DIR}/missing.csv RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT err MATCHES "missing.csv: no such file")
  message(FATAL_ERROR "installed cullide plot does not find ${prefix}/share/cullide/tools/plot.py: ${err}")
endif()

# 3. pkg-config.
find_program(PKG_CONFIG pkg-config)
if(PKG_CONFIG)
  set(ENV{PKG_CONFIG_PATH} "${prefix}/lib/pkgconfig")
  run(${PKG_CONFIG} --modversion cullide)
  if(NOT last_output MATCHES "^${VERSION}")
    message(FATAL_ERROR "pkg-config --modversion cullide: ${last_output}")
  endif()
  run(${PKG_CONFIG} --cflags --libs cullide)
  if(NOT last_output MATCHES "-I${prefix}/lib/pkgconfig/../../include")
    message(FATAL_ERROR "pkg-config --cflags cullide does not point into the prefix: ${last_output}")
  endif()
endif()

# 4. The installed Python package.
if(PYTHON)
  set(ENV{PYTHONPATH} "${prefix}/lib/python3/dist-packages")
  set(ENV{PYTHONDONTWRITEBYTECODE} 1)
  # (newlines, not semicolons: a ';' would split the argument into a CMake list)
  run(${PYTHON} -c "import cullide, os\nprint(cullide.__version__)\nprint(os.path.realpath(cullide.data_dir()))"
      WORKING_DIRECTORY ${WORK_DIR})
  if(NOT last_output MATCHES "^${VERSION}\n${prefix}/share/cullide/data")
    message(FATAL_ERROR "installed Python package: ${last_output}")
  endif()
endif()
message(STATUS "install test passed: ${prefix}")
