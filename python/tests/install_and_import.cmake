# Script of the python_install test (python/CMakeLists.txt): `cmake --install` into a scratch
# prefix, then Debian's python3 imports the package hsr (its extension and Python modules) from
# there alone (-P: not from the working directory) and runs the manual's examples.
file(REMOVE_RECURSE ${SCRATCH})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${HSR_BUILD_DIR} --prefix ${SCRATCH} RESULT_VARIABLE rc OUTPUT_QUIET)
if(rc)
  message(FATAL_ERROR "install failed: ${rc}")
endif()
set(site ${SCRATCH}/${HSR_PYTHON_INSTALL_DIR})
foreach(example five_lines batch)
  execute_process(COMMAND ${CMAKE_COMMAND} -E env PYTHONPATH=${site} ${PYTHON} -P -c
                          "import hsr, hsr.distributed, runpy, sys; assert hsr.distributed.__file__.startswith(sys.argv[1]), hsr.distributed.__file__; runpy.run_path(sys.argv[2])"
                          ${site} ${EXAMPLES}/${example}.py
                  WORKING_DIRECTORY ${SCRATCH} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${example}: ${out}${err}")
  if(rc)
    message(FATAL_ERROR "${example}.py with the installed module failed: ${rc}")
  endif()
endforeach()
