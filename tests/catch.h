// Catch2 for catgraph's tests. Include this instead of <catch2/catch.hpp>.
//
// Ceres includes glog, whose CHECK macro would silently replace Catch2's
// whenever a Ceres header comes after Catch2: the assertion then aborts on
// failure instead of being reported, and is not counted. Ceres (whose inline
// code uses glog's CHECK) and glog are included first here and glog's CHECK
// is dropped; their include guards keep it from coming back.
#ifndef CATGRAPH_TESTS_CATCH_H_
#define CATGRAPH_TESTS_CATCH_H_

#include <ceres/ceres.h>
#include <glog/logging.h>
#undef CHECK

#include <catch2/catch.hpp>

#endif  // CATGRAPH_TESTS_CATCH_H_
