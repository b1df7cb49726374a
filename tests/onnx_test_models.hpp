#pragma once
// Tiny ONNX models written byte by byte (the protobuf wire format), for the segmenter tests: OpenCV
// cannot export ONNX and no small model ships with the system. Only the fields the models below
// need are written (onnx/onnx.proto3 field numbers).

#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

namespace cge_test {
namespace onnx {

/// A protobuf message under construction.
class Message {
 public:
  Message& varint_field(std::uint32_t field, std::uint64_t value) {
    tag(field, 0);
    varint(value);
    return *this;
  }
  Message& bytes_field(std::uint32_t field, const std::string& value) {
    tag(field, 2);
    varint(value.size());
    bytes_ += value;
    return *this;
  }
  Message& message_field(std::uint32_t field, const Message& m) { return bytes_field(field, m.bytes_); }
  const std::string& bytes() const { return bytes_; }

 private:
  void tag(std::uint32_t field, std::uint32_t wire_type) { varint((std::uint64_t{field} << 3) | wire_type); }
  void varint(std::uint64_t v) {
    while (v >= 0x80) {
      bytes_ += static_cast<char>((v & 0x7f) | 0x80);
      v >>= 7;
    }
    bytes_ += static_cast<char>(v);
  }
  std::string bytes_;
};

constexpr int kFloat = 1;  // TensorProto.DataType
constexpr int kInt64 = 7;

/// ValueInfoProto of a tensor; a dimension < 0 is written as the symbolic dimension "N".
inline Message value_info(const std::string& name, const std::vector<std::int64_t>& dims, int elem_type = kFloat) {
  Message shape;
  for (const std::int64_t d : dims) {
    Message dim;
    if (d >= 0) {
      dim.varint_field(1, static_cast<std::uint64_t>(d));
    } else {
      dim.bytes_field(2, "N");
    }
    shape.message_field(1, dim);
  }
  Message tensor_type;
  tensor_type.varint_field(1, static_cast<std::uint64_t>(elem_type)).message_field(2, shape);
  Message type;
  type.message_field(1, tensor_type);
  Message info;
  info.bytes_field(1, name).message_field(2, type);
  return info;
}

/// NodeProto with integer-list attributes.
struct Attribute {
  std::string name;
  std::vector<std::int64_t> ints;
};
inline Message node(const std::string& op, const std::vector<std::string>& inputs,
                    const std::vector<std::string>& outputs, const std::vector<Attribute>& attributes = {}) {
  Message n;
  for (const auto& i : inputs) n.bytes_field(1, i);
  for (const auto& o : outputs) n.bytes_field(2, o);
  n.bytes_field(3, op + "_" + outputs.front());
  n.bytes_field(4, op);
  for (const auto& a : attributes) {
    Message attr;
    attr.bytes_field(1, a.name);
    for (const std::int64_t v : a.ints) attr.varint_field(8, static_cast<std::uint64_t>(v));
    attr.varint_field(20, 7);  // AttributeProto.INTS
    n.message_field(5, attr);
  }
  return n;
}

inline Message float_tensor(const std::string& name, const std::vector<std::int64_t>& dims,
                            const std::vector<float>& values) {
  Message t;
  for (const std::int64_t d : dims) t.varint_field(1, static_cast<std::uint64_t>(d));
  t.varint_field(2, kFloat).bytes_field(8, name);
  std::string raw(values.size() * sizeof(float), '\0');  // little-endian, as on the test machines
  std::memcpy(&raw[0], values.data(), raw.size());
  t.bytes_field(9, raw);
  return t;
}

inline Message int64_tensor(const std::string& name, const std::vector<std::int64_t>& values) {
  Message t;
  t.varint_field(1, values.size()).varint_field(2, kInt64).bytes_field(8, name);
  std::string raw(values.size() * sizeof(std::int64_t), '\0');
  std::memcpy(&raw[0], values.data(), raw.size());
  t.bytes_field(9, raw);
  return t;
}

/// ModelProto (IR version 7, default opset 13) around a graph.
inline std::string model(const Message& graph) {
  Message opset;
  opset.varint_field(2, 13);
  Message m;
  m.varint_field(1, 7).bytes_field(2, "cge-test").message_field(7, graph).message_field(8, opset);
  return m.bytes();
}

/// Graph of one element-wise node per output, all reading the input `images`.
inline std::string elementwise_model(const std::vector<std::int64_t>& input_dims, int outputs = 1,
                                     const std::vector<std::int64_t>& extra_input_dims = {}) {
  Message g;
  const char* ops[] = {"Relu", "Sigmoid", "Abs"};
  for (int i = 0; i < outputs; ++i) g.message_field(1, node(ops[i % 3], {"images"}, {"out" + std::to_string(i)}));
  g.bytes_field(2, "elementwise");
  g.message_field(11, value_info("images", input_dims));
  if (!extra_input_dims.empty()) g.message_field(11, value_info("extra", extra_input_dims));
  for (int i = 0; i < outputs; ++i) g.message_field(12, value_info("out" + std::to_string(i), input_dims));
  return model(g);
}

/// The values a YoloShapedModel produces for every anchor, whatever the image: a constant
/// prediction column (box, 80 scores, 32 coefficients) and constant prototype planes.
struct YoloConstants {
  std::vector<float> prediction;  ///< 116 values (fewer or more to make a wrongly shaped model)
  std::vector<float> prototype;   ///< 32 values: the value of each prototype plane
};

/// A model with the input and output shapes of YOLOv8-seg for a side x side input whose outputs
/// do not depend on the image: two max-pool + 1x1 convolution branches with zero weights, whose
/// biases are the constants. Predictions: pool to 3 x 7 = 21 cells, the anchor count of a 32 x 32
/// input (16 + 4 + 1), so side must be 32 for the prediction shape to match.
inline std::string yolo_shaped_model(const YoloConstants& c, int side = 32) {
  const auto rows = static_cast<std::int64_t>(c.prediction.size());
  const auto planes = static_cast<std::int64_t>(c.prototype.size());
  const std::int64_t pooled_h = 3, pooled_w = 7;
  Message g;
  g.message_field(1, node("MaxPool", {"images"}, {"pooled_p"},
                          {{"kernel_shape", {side - pooled_h + 1, side - pooled_w + 1}}, {"strides", {1, 1}}}));
  g.message_field(1, node("Conv", {"pooled_p", "w_p", "b_p"}, {"conv_p"}, {{"kernel_shape", {1, 1}}}));
  g.message_field(1, node("Reshape", {"conv_p", "shape_p"}, {"output0"}));
  g.message_field(1, node("MaxPool", {"images"}, {"pooled_m"}, {{"kernel_shape", {4, 4}}, {"strides", {4, 4}}}));
  g.message_field(1, node("Conv", {"pooled_m", "w_m", "b_m"}, {"output1"}, {{"kernel_shape", {1, 1}}}));
  g.bytes_field(2, "yolo_shaped");
  g.message_field(5, float_tensor("w_p", {rows, 3, 1, 1}, std::vector<float>(static_cast<std::size_t>(rows * 3), 0.f)));
  g.message_field(5, float_tensor("b_p", {rows}, c.prediction));
  g.message_field(5, int64_tensor("shape_p", {1, rows, pooled_h * pooled_w}));
  g.message_field(
      5, float_tensor("w_m", {planes, 3, 1, 1}, std::vector<float>(static_cast<std::size_t>(planes * 3), 0.f)));
  g.message_field(5, float_tensor("b_m", {planes}, c.prototype));
  g.message_field(11, value_info("images", {1, 3, side, side}));
  g.message_field(12, value_info("output0", {1, rows, pooled_h * pooled_w}));
  g.message_field(12, value_info("output1", {1, planes, side / 4, side / 4}));
  return model(g);
}

inline void write_file(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

}  // namespace onnx
}  // namespace cge_test
