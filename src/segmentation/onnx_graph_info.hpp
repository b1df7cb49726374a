#pragma once
// Reads the declared inputs and outputs of an ONNX model straight from its protobuf bytes.
//
// Internal to cge::pipeline. OpenCV 4.6's DNN module cannot report a network's input shape (and
// crashes when asked without one), yet a YOLOv8 export only runs at its fixed input size, so the
// segmenter reads the size from the file itself. Only the few ONNX fields needed are decoded; every
// other field is skipped by its wire type.

#include <cstdint>
#include <string>
#include <vector>

namespace cge {
namespace detail {

/// A graph input or output as declared in the model (ValueInfoProto).
struct OnnxValueInfo {
  std::string name;
  int elem_type = 0;               ///< ONNX TensorProto.DataType: 1 = float, 0 = not declared
  std::vector<std::int64_t> dims;  ///< declared dimensions; -1 where symbolic or not given
  bool has_shape = false;          ///< false when the model declares no shape at all
};

struct OnnxGraphInfo {
  std::vector<OnnxValueInfo> inputs;  ///< graph inputs that are not initializers (weights)
  std::vector<OnnxValueInfo> outputs;
};

/// Decodes the model's graph inputs and outputs. Throws std::invalid_argument naming `source` when
/// the bytes are not a well-formed ONNX ModelProto with a graph.
OnnxGraphInfo read_onnx_graph_info(const std::vector<unsigned char>& bytes, const std::string& source);

}  // namespace detail
}  // namespace cge
