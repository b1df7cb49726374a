#pragma once
// The names of a sequence folder in the TUM RGB-D layout, as cge_sim writes it and the dataset
// reader finds it (docs/DATASETS.md): TUM's own lists and ground truth, plus this project's mask
// folders, camera settings and ground-truth loops. One place, so writer and reader cannot drift.

namespace cge {
namespace dataset {
namespace tum_layout {

inline constexpr const char* kRgbList = "rgb.txt";                   ///< TUM: timestamp rgb/<stamp>.png
inline constexpr const char* kDepthList = "depth.txt";               ///< TUM: timestamp depth/<stamp>.png
inline constexpr const char* kAssociationsFile = "associations.txt";  ///< associate.py's output
inline constexpr const char* kGroundTruthFile = "groundtruth.txt";   ///< TUM trajectory of the camera
inline constexpr const char* kRgbDir = "rgb";                        ///< colour images
inline constexpr const char* kDepthDir = "depth";                    ///< 16-bit depth images
inline constexpr const char* kMasksDir = "masks";                    ///< exact instance labels (synthetic)
inline constexpr const char* kSegmentationDir = "segmentation";      ///< labels after the error model
inline constexpr const char* kInstancesFile = "instances.csv";       ///< in each label folder
inline constexpr const char* kCameraFile = "camera.yaml";            ///< ORB-SLAM2 settings of the camera
inline constexpr const char* kLoopsFile = "loops.txt";               ///< ground-truth loops (synthetic)
inline constexpr const char* kImageExtension = ".png";               ///< every image and label file

}  // namespace tum_layout
}  // namespace dataset
}  // namespace cge
