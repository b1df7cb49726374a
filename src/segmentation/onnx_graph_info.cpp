#include "onnx_graph_info.hpp"

#include <algorithm>
#include <stdexcept>
#include <string_view>
#include <unordered_set>

namespace cge {
namespace detail {
namespace {

// Field numbers of the ONNX protobuf schema (onnx/onnx.proto3) that are read here.
constexpr std::uint32_t kModelGraph = 7;
constexpr std::uint32_t kGraphInitializer = 5;
constexpr std::uint32_t kGraphInput = 11;
constexpr std::uint32_t kGraphOutput = 12;
constexpr std::uint32_t kTensorName = 8;
constexpr std::uint32_t kValueInfoName = 1;
constexpr std::uint32_t kValueInfoType = 2;
constexpr std::uint32_t kTypeTensorType = 1;
constexpr std::uint32_t kTensorTypeElemType = 1;
constexpr std::uint32_t kTensorTypeShape = 2;
constexpr std::uint32_t kShapeDim = 1;
constexpr std::uint32_t kDimValue = 1;

// Protobuf wire types.
constexpr std::uint32_t kWireVarint = 0;
constexpr std::uint32_t kWireFixed64 = 1;
constexpr std::uint32_t kWireLengthDelimited = 2;
constexpr std::uint32_t kWireFixed32 = 5;

constexpr int kMaxVarintBytes = 10;
constexpr int kBitsPerVarintByte = 7;
constexpr unsigned kVarintPayloadMask = 0x7f;
constexpr unsigned kVarintContinueBit = 0x80;
constexpr std::uint64_t kFixed64Bytes = 8;
constexpr std::uint64_t kFixed32Bytes = 4;
constexpr int kTagWireTypeBits = 3;
constexpr std::uint64_t kTagWireTypeMask = 7;

class ParseError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Field {
  std::uint32_t number = 0;
  std::uint32_t wire_type = 0;
  std::uint64_t varint = 0;  // wire type 0
  std::string_view bytes;    // wire type 2
};

// A view of one protobuf message; `base` is the offset of its first byte in the file, for errors.
class Reader {
 public:
  Reader(std::string_view data, std::size_t base) : data_(data), base_(base) {}

  bool done() const { return pos_ == data_.size(); }

  Field next() {
    Field f;
    const std::uint64_t tag = varint();
    f.number = static_cast<std::uint32_t>(tag >> kTagWireTypeBits);
    f.wire_type = static_cast<std::uint32_t>(tag & kTagWireTypeMask);
    if (f.number == 0) fail("field number 0");
    switch (f.wire_type) {
      case kWireVarint:
        f.varint = varint();
        break;
      case kWireFixed64:
        skip(kFixed64Bytes);
        break;
      case kWireFixed32:
        skip(kFixed32Bytes);
        break;
      case kWireLengthDelimited: {
        const std::uint64_t length = varint();
        if (length > data_.size() - pos_) fail("a length that runs past the end of its message");
        f.bytes = data_.substr(pos_, static_cast<std::size_t>(length));
        pos_ += static_cast<std::size_t>(length);
        break;
      }
      default:
        fail("wire type " + std::to_string(f.wire_type));
    }
    return f;
  }

  // The reader of a length-delimited field returned by the last next().
  Reader sub(const Field& f) const {
    return Reader(f.bytes, base_ + static_cast<std::size_t>(f.bytes.data() - data_.data()));
  }

 private:
  std::uint64_t varint() {
    std::uint64_t value = 0;
    for (int i = 0; i < kMaxVarintBytes; ++i) {
      if (pos_ == data_.size()) fail("a number cut off by the end of its message");
      const auto byte = static_cast<unsigned char>(data_[pos_++]);
      value |= static_cast<std::uint64_t>(byte & kVarintPayloadMask) << (kBitsPerVarintByte * i);
      if ((byte & kVarintContinueBit) == 0) return value;
    }
    fail("a number longer than 10 bytes");
  }

  void skip(std::uint64_t n) {
    if (n > data_.size() - pos_) fail("a fixed-size field cut off by the end of its message");
    pos_ += static_cast<std::size_t>(n);
  }

  [[noreturn]] void fail(const std::string& what) const {
    throw ParseError(what + " at byte " + std::to_string(base_ + pos_));
  }

  std::string_view data_;
  std::size_t base_;
  std::size_t pos_ = 0;
};

void read_shape(Reader r, OnnxValueInfo& info) {
  info.has_shape = true;
  while (!r.done()) {
    const Field f = r.next();
    if (f.number != kShapeDim || f.wire_type != kWireLengthDelimited) continue;
    std::int64_t dim = -1;  // dim_param (symbolic) or nothing: unknown
    Reader d = r.sub(f);
    while (!d.done()) {
      const Field g = d.next();
      if (g.number == kDimValue && g.wire_type == kWireVarint) dim = static_cast<std::int64_t>(g.varint);
    }
    info.dims.push_back(dim);
  }
}

OnnxValueInfo read_value_info(Reader r) {
  OnnxValueInfo info;
  while (!r.done()) {
    const Field f = r.next();
    if (f.number == kValueInfoName && f.wire_type == kWireLengthDelimited) {
      info.name = std::string(f.bytes);
    } else if (f.number == kValueInfoType && f.wire_type == kWireLengthDelimited) {
      Reader type = r.sub(f);
      while (!type.done()) {
        const Field t = type.next();
        if (t.number != kTypeTensorType || t.wire_type != kWireLengthDelimited) continue;
        Reader tensor = type.sub(t);
        while (!tensor.done()) {
          const Field g = tensor.next();
          if (g.number == kTensorTypeElemType && g.wire_type == kWireVarint) {
            info.elem_type = static_cast<int>(g.varint);
          } else if (g.number == kTensorTypeShape && g.wire_type == kWireLengthDelimited) {
            read_shape(tensor.sub(g), info);
          }
        }
      }
    }
  }
  return info;
}

std::string initializer_name(Reader r) {
  std::string name;
  while (!r.done()) {
    const Field f = r.next();
    if (f.number == kTensorName && f.wire_type == kWireLengthDelimited) name = std::string(f.bytes);
  }
  return name;
}

OnnxGraphInfo read_graph(Reader r) {
  OnnxGraphInfo info;
  std::vector<OnnxValueInfo> declared_inputs;
  std::unordered_set<std::string> initializers;
  while (!r.done()) {
    const Field f = r.next();
    if (f.wire_type != kWireLengthDelimited) continue;
    if (f.number == kGraphInitializer) initializers.insert(initializer_name(r.sub(f)));
    if (f.number == kGraphInput) declared_inputs.push_back(read_value_info(r.sub(f)));
    if (f.number == kGraphOutput) info.outputs.push_back(read_value_info(r.sub(f)));
  }
  // Older exporters (IR version < 4) list every weight as a graph input too.
  for (auto& input : declared_inputs) {
    if (initializers.count(input.name) == 0) info.inputs.push_back(std::move(input));
  }
  return info;
}

}  // namespace

OnnxGraphInfo read_onnx_graph_info(const std::vector<unsigned char>& bytes, const std::string& source) {
  const std::string_view data(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  try {
    Reader model(data, 0);
    bool has_graph = false;
    OnnxGraphInfo info;
    while (!model.done()) {
      const Field f = model.next();
      if (f.number == kModelGraph && f.wire_type == kWireLengthDelimited) {
        info = read_graph(model.sub(f));
        has_graph = true;
      }
    }
    if (!has_graph) throw ParseError("no graph in the model");
    return info;
  } catch (const ParseError& e) {
    throw std::invalid_argument(source + " is not an ONNX model (protobuf: " + e.what() + ")");
  }
}

}  // namespace detail
}  // namespace cge
