# `cmake --install BUILD --prefix P` puts the catgraph command in P/bin, the
# headers in P/include/catgraph (their source layout), the libraries in
# P/lib and a relocatable package in P/lib/cmake/catgraph, so that a
# consumer's
#
#   find_package(catgraph REQUIRED)
#   target_link_libraries(app PRIVATE catgraph::backend)
#
# finds every library as catgraph::NAME with its dependencies (docs/library.md).
include(CMakePackageConfigHelpers)

set(catgraph_exported graph io image_io backend frontend hierarchy mapping simulation plot experiments)
foreach(name IN LISTS catgraph_exported)
  set_target_properties(catgraph_${name} PROPERTIES EXPORT_NAME ${name})
  list(APPEND catgraph_exported_targets catgraph_${name})
endforeach()

install(TARGETS ${catgraph_exported_targets} EXPORT catgraphTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(TARGETS catgraph RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
foreach(dir backend frontend hierarchy mapping simulation apps/plot experiments)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${dir}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/catgraph/${dir}
    FILES_MATCHING PATTERN "*.h" PATTERN "scenarios" EXCLUDE)
endforeach()

set(catgraph_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/catgraph)
install(EXPORT catgraphTargets NAMESPACE catgraph:: DESTINATION ${catgraph_cmake_dir})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/catgraphConfig.cmake.in
  ${PROJECT_BINARY_DIR}/catgraphConfig.cmake INSTALL_DESTINATION ${catgraph_cmake_dir})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/catgraphConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/catgraphConfig.cmake ${PROJECT_BINARY_DIR}/catgraphConfigVersion.cmake
  DESTINATION ${catgraph_cmake_dir})
