#pragma once
// The Ceres headers the cge adapters use, included in one place. Ceres' headers include glog, whose
// CHECK macro silently replaces one defined before (Catch2's CHECK in a test file that includes
// catch.hpp first: its checks would then abort the program on failure). A CHECK defined before this
// header is therefore restored after it; with none defined before, glog's stays.
#ifdef CHECK
#define CGE_CERES_HEADERS_RESTORE_CHECK
#pragma push_macro("CHECK")
#endif

#include <ceres/autodiff_cost_function.h>
#include <ceres/loss_function.h>
#include <ceres/manifold.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <ceres/types.h>

#ifdef CGE_CERES_HEADERS_RESTORE_CHECK
#pragma pop_macro("CHECK")
#undef CGE_CERES_HEADERS_RESTORE_CHECK
#endif
