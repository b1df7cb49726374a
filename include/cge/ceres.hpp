#pragma once
// The Ceres adapters (target cge::ceres): pose refinement, pose-graph optimisation and bundle
// adjustment, header-only over Ceres 2.1, Eigen and the core.
#include "cge/ceres/bundle_adjustment.hpp"
#include "cge/ceres/pose_graph.hpp"
#include "cge/ceres/pose_refinement.hpp"
