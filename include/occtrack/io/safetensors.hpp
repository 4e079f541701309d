// safetensors files (https://github.com/huggingface/safetensors, format description in its README): an
// 8-byte little-endian header length, a JSON header mapping each tensor name to {dtype, shape,
// data_offsets} plus an optional "__metadata__" string-to-string map, then the raw little-endian data.
// occtrack's datasets and models use it so that they load in PyTorch (safetensors.torch.load_file) and
// elsewhere without this project.
//
//   io::TensorFile file;
//   file.metadata["format"] = "occtrack.model.v1";
//   file.put("norm.cloud.mean", {2}, std::vector<float>{0.f, 0.f});
//   io::write_safetensors("model.safetensors", file);
//   io::TensorFile back = io::read_safetensors("model.safetensors");   // throws io::InputError
//   const io::Tensor& t = back.at("norm.cloud.mean");                  // throws, naming file and tensor
//
// Supported dtypes: F32, F64, I32, I64 (others are refused with a message naming the tensor and dtype).
// Tensors are kept in their file dtype; as_float()/as_double() convert.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace occtrack::io {

enum class DType { F32, F64, I32, I64 };

const char* dtype_name(DType dtype);
std::size_t dtype_size(DType dtype);
/// "[3, 4]": a shape as messages print it.
std::string shape_text(const std::vector<std::int64_t>& shape);

struct Tensor {
  DType dtype = DType::F32;
  std::vector<std::int64_t> shape;
  std::vector<unsigned char> bytes;  ///< little-endian, row-major, numel * dtype_size

  std::int64_t numel() const;
  /// Values converted to float / double (integers converted exactly where representable).
  std::vector<float> as_float() const;
  std::vector<double> as_double() const;
  /// "[3, 4]"
  std::string shape_text() const;
};

struct TensorFile {
  std::string source;  ///< file name for messages (set by read_safetensors)
  std::map<std::string, std::string> metadata;
  std::map<std::string, Tensor> tensors;

  bool has(const std::string& name) const { return tensors.count(name) != 0; }
  /// The tensor; throws InputError "SOURCE: tensor 'NAME' is missing" otherwise.
  const Tensor& at(const std::string& name) const;
  /// The tensor, which must have exactly `shape`; throws InputError naming the tensor, the expected and the
  /// actual shape otherwise.
  const Tensor& at(const std::string& name, const std::vector<std::int64_t>& shape) const;
  /// Metadata value; throws InputError "SOURCE: metadata 'KEY' is missing" otherwise.
  const std::string& meta(const std::string& key) const;

  /// Adds (or replaces) a tensor; values.size() must equal the product of shape (std::invalid_argument).
  void put(const std::string& name, const std::vector<std::int64_t>& shape, const std::vector<float>& values);
  void put(const std::string& name, const std::vector<std::int64_t>& shape, const std::vector<double>& values);
  void put(const std::string& name, const std::vector<std::int64_t>& shape,
           const std::vector<std::int32_t>& values);
  void put(const std::string& name, const std::vector<std::int64_t>& shape,
           const std::vector<std::int64_t>& values);
  /// Raw bytes (must hold numel * dtype_size bytes, little-endian).
  void put_raw(const std::string& name, DType dtype, const std::vector<std::int64_t>& shape, const void* data);
};

/// Reads and validates a whole file: header length within the file, JSON header, known dtypes, shapes that
/// match their byte ranges, ranges inside the data and not overlapping. Throws InputError naming the file
/// and what is wrong.
TensorFile read_safetensors(const std::string& path);
TensorFile parse_safetensors(const std::vector<unsigned char>& bytes, const std::string& source);
/// Writes tensors in name order, data aligned to 8 bytes. Throws InputError when the file cannot be written.
void write_safetensors(const std::string& path, const TensorFile& file);
std::vector<unsigned char> serialize_safetensors(const TensorFile& file);

}  // namespace occtrack::io
