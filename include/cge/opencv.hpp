#pragma once
// Umbrella header of the OpenCV adapters (link cge::opencv): cv::KeyPoint and cv::Point_ as point
// types, cv::Mat depth images and masks, cv::Rect boxes.

#include "cge/opencv/depth.hpp"
#include "cge/opencv/keypoint.hpp"
#include "cge/opencv/mask.hpp"
#include "cge/opencv/pixel_box.hpp"
#include "cge/opencv/undistort.hpp"
