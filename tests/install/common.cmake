# Shared by run_downstream.cmake and run_package.cmake (included with -P
# scripts' own variables: DOWNSTREAM_DIR, C_COMPILER, CXX_COMPILER, LAUNCHER).

# Runs a command; fails the test with its output when it fails. `out` holds
# its standard output afterwards.
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  set(out "${out}" PARENT_SCOPE)
endfunction()

# Configures and builds tests/install/downstream in `build_dir` against the
# tsmh package found under `prefix`, with the same compilers as the project,
# and runs its `downstream` program (its output in `out`).
function(build_downstream build_dir prefix)
  set(args -S ${DOWNSTREAM_DIR} -B ${build_dir} -DCMAKE_PREFIX_PATH=${prefix}
      -DCMAKE_C_COMPILER=${C_COMPILER} -DCMAKE_CXX_COMPILER=${CXX_COMPILER}
      -DCMAKE_BUILD_TYPE=Release)
  if(LAUNCHER)
    list(APPEND args -DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER} -DCMAKE_C_COMPILER_LAUNCHER=${LAUNCHER})
  endif()
  run(${CMAKE_COMMAND} ${args})
  run(${CMAKE_COMMAND} --build ${build_dir} -j2)
  run(${build_dir}/downstream)
  set(out "${out}" PARENT_SCOPE)
endfunction()
