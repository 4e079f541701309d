#include "occtrack/io/safetensors.hpp"

#include <algorithm>
#include <bit>
#include <cstring>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "json_util.hpp"
#include "occtrack/io/error.hpp"

namespace occtrack::io {

static_assert(std::endian::native == std::endian::little, "safetensors data is little-endian; big-endian hosts are not supported");

namespace {

using nlohmann::json;

// Refuse headers beyond this: a corrupt length must not make us allocate gigabytes.
constexpr std::uint64_t kMaxHeaderBytes = 100u << 20;

[[noreturn]] void fail(const std::string& source, const std::string& what) { throw InputError(source + ": " + what); }

bool parse_dtype(const std::string& text, DType& out) {
  if (text == "F32") out = DType::F32;
  else if (text == "F64") out = DType::F64;
  else if (text == "I32") out = DType::I32;
  else if (text == "I64") out = DType::I64;
  else return false;
  return true;
}

template <typename T>
std::vector<T> convert(const Tensor& t) {
  const auto n = static_cast<std::size_t>(t.numel());
  std::vector<T> out(n);
  auto copy = [&](auto tag) {
    using S = decltype(tag);
    for (std::size_t i = 0; i < n; ++i) {
      S v;
      std::memcpy(&v, t.bytes.data() + i * sizeof(S), sizeof(S));
      out[i] = static_cast<T>(v);
    }
  };
  switch (t.dtype) {
    case DType::F32: copy(float{}); break;
    case DType::F64: copy(double{}); break;
    case DType::I32: copy(std::int32_t{}); break;
    case DType::I64: copy(std::int64_t{}); break;
  }
  return out;
}

std::int64_t product(const std::vector<std::int64_t>& shape) {
  std::int64_t n = 1;
  for (auto d : shape) n *= d;
  return n;
}

template <typename T>
void put_values(TensorFile& file, const std::string& name, DType dtype, const std::vector<std::int64_t>& shape,
                const std::vector<T>& values) {
  for (auto d : shape)
    if (d < 0) throw std::invalid_argument("safetensors: tensor '" + name + "' has a negative dimension");
  if (static_cast<std::int64_t>(values.size()) != product(shape))
    throw std::invalid_argument("safetensors: tensor '" + name + "' has " + std::to_string(values.size()) +
                                " values for shape " + shape_text(shape));
  file.put_raw(name, dtype, shape, values.data());
}

}  // namespace

const char* dtype_name(DType dtype) {
  switch (dtype) {
    case DType::F32: return "F32";
    case DType::F64: return "F64";
    case DType::I32: return "I32";
    case DType::I64: return "I64";
  }
  return "?";
}

std::size_t dtype_size(DType dtype) { return dtype == DType::F32 || dtype == DType::I32 ? 4 : 8; }

std::int64_t Tensor::numel() const { return product(shape); }
std::vector<float> Tensor::as_float() const { return convert<float>(*this); }
std::vector<double> Tensor::as_double() const { return convert<double>(*this); }
std::string shape_text(const std::vector<std::int64_t>& shape) {
  std::string s = "[";
  for (std::size_t i = 0; i < shape.size(); ++i) s += (i ? ", " : "") + std::to_string(shape[i]);
  return s + "]";
}

std::string Tensor::shape_text() const { return io::shape_text(shape); }

const Tensor& TensorFile::at(const std::string& name) const {
  auto it = tensors.find(name);
  if (it == tensors.end()) fail(source.empty() ? "safetensors" : source, "tensor '" + name + "' is missing");
  return it->second;
}

const Tensor& TensorFile::at(const std::string& name, const std::vector<std::int64_t>& shape) const {
  const Tensor& t = at(name);
  if (t.shape != shape)
    fail(source.empty() ? "safetensors" : source,
         "tensor '" + name + "' has shape " + t.shape_text() + ", expected " + shape_text(shape));
  return t;
}

const std::string& TensorFile::meta(const std::string& key) const {
  auto it = metadata.find(key);
  if (it == metadata.end()) fail(source.empty() ? "safetensors" : source, "metadata '" + key + "' is missing");
  return it->second;
}

void TensorFile::put(const std::string& name, const std::vector<std::int64_t>& shape, const std::vector<float>& values) {
  put_values(*this, name, DType::F32, shape, values);
}
void TensorFile::put(const std::string& name, const std::vector<std::int64_t>& shape,
                     const std::vector<double>& values) {
  put_values(*this, name, DType::F64, shape, values);
}
void TensorFile::put(const std::string& name, const std::vector<std::int64_t>& shape,
                     const std::vector<std::int32_t>& values) {
  put_values(*this, name, DType::I32, shape, values);
}
void TensorFile::put(const std::string& name, const std::vector<std::int64_t>& shape,
                     const std::vector<std::int64_t>& values) {
  put_values(*this, name, DType::I64, shape, values);
}

void TensorFile::put_raw(const std::string& name, DType dtype, const std::vector<std::int64_t>& shape,
                         const void* data) {
  if (name.empty() || name == "__metadata__")
    throw std::invalid_argument("safetensors: invalid tensor name '" + name + "'");
  Tensor t;
  t.dtype = dtype;
  t.shape = shape;
  const std::size_t bytes = static_cast<std::size_t>(product(shape)) * dtype_size(dtype);
  t.bytes.resize(bytes);
  if (bytes) std::memcpy(t.bytes.data(), data, bytes);
  tensors[name] = std::move(t);
}

TensorFile parse_safetensors(const std::vector<unsigned char>& bytes, const std::string& source) {
  if (bytes.size() < 8) fail(source, "not a safetensors file: " + std::to_string(bytes.size()) + " bytes, fewer than the 8-byte header length");
  std::uint64_t header_size = 0;
  std::memcpy(&header_size, bytes.data(), 8);
  if (header_size > kMaxHeaderBytes || header_size > bytes.size() - 8)
    fail(source, "not a safetensors file: header length " + std::to_string(header_size) + " exceeds the file (" +
                     std::to_string(bytes.size()) + " bytes)");
  const std::string header_text(reinterpret_cast<const char*>(bytes.data() + 8), header_size);
  json header;
  try {
    header = json::parse(header_text);
  } catch (const json::exception& e) {
    // parse_error, and out_of_range for a number beyond double's range (1e400): both are bad input.
    fail(source, std::string("safetensors header is not valid JSON: ") + e.what());
  }
  if (!header.is_object()) fail(source, "safetensors header is not a JSON object");
  const std::size_t data_begin = 8 + header_size;
  const std::size_t data_size = bytes.size() - data_begin;

  TensorFile file;
  file.source = source;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> ranges;
  for (auto it = header.begin(); it != header.end(); ++it) {
    const std::string& name = it.key();
    const json& entry = it.value();
    if (name == "__metadata__") {
      if (!entry.is_object()) fail(source, "__metadata__ must be an object of strings");
      for (auto m = entry.begin(); m != entry.end(); ++m) {
        if (!m.value().is_string()) fail(source, "__metadata__." + detail::printable(m.key()) + " must be a string");
        file.metadata[m.key()] = m.value().get<std::string>();
      }
      continue;
    }
    const std::string where = "tensor '" + detail::printable(name) + "'";
    if (!entry.is_object() || !entry.contains("dtype") || !entry.contains("shape") || !entry.contains("data_offsets"))
      fail(source, where + " needs dtype, shape and data_offsets");
    if (!entry["dtype"].is_string()) fail(source, where + ": dtype must be a string");
    Tensor t;
    const std::string dtype = entry["dtype"].get<std::string>();
    if (!parse_dtype(dtype, t.dtype))
      fail(source, where + " has dtype " + detail::printable(dtype) + " (supported: F32, F64, I32, I64)");
    const json& shape = entry["shape"];
    if (!shape.is_array()) fail(source, where + ": shape must be a list");
    std::uint64_t numel = 1;
    for (const auto& d : shape) {
      if (!d.is_number_unsigned()) fail(source, where + ": shape entries must be non-negative integers");
      const auto v = d.get<std::uint64_t>();
      // Each dimension on its own too: after a 0, the product stays 0 whatever follows, and a dimension
      // beyond int64 would be stored negative ([0, 18446744073709551615]; tests/test_fuzz_regressions.cpp).
      if (v > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()) ||
          (v != 0 && numel > std::numeric_limits<std::uint64_t>::max() / 16 / v))
        fail(source, where + ": shape is too large");
      numel *= v;
      t.shape.push_back(static_cast<std::int64_t>(v));
    }
    const json& offsets = entry["data_offsets"];
    if (!offsets.is_array() || offsets.size() != 2 || !offsets[0].is_number_unsigned() ||
        !offsets[1].is_number_unsigned())
      fail(source, where + ": data_offsets must be two non-negative integers");
    const auto begin = offsets[0].get<std::uint64_t>(), end = offsets[1].get<std::uint64_t>();
    if (begin > end || end > data_size)
      fail(source, where + ": data_offsets [" + std::to_string(begin) + ", " + std::to_string(end) +
                       "] lie outside the data (" + std::to_string(data_size) + " bytes)");
    if (end - begin != numel * dtype_size(t.dtype))
      fail(source, where + ": shape " + t.shape_text() + " of " + dtype + " needs " +
                       std::to_string(numel * dtype_size(t.dtype)) + " bytes, data_offsets give " +
                       std::to_string(end - begin));
    ranges.emplace_back(begin, end);
    t.bytes.assign(bytes.begin() + static_cast<std::ptrdiff_t>(data_begin + begin),
                   bytes.begin() + static_cast<std::ptrdiff_t>(data_begin + end));
    file.tensors[name] = std::move(t);
  }
  std::sort(ranges.begin(), ranges.end());
  for (std::size_t i = 1; i < ranges.size(); ++i)
    if (ranges[i].first < ranges[i - 1].second) fail(source, "two tensors share bytes (overlapping data_offsets)");
  return file;
}

TensorFile read_safetensors(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open file");
  in.seekg(0, std::ios::end);
  const auto size = in.tellg();
  if (size < 0) throw InputError(path + ": cannot read file");
  in.seekg(0);
  std::vector<unsigned char> bytes(static_cast<std::size_t>(size));
  if (size > 0 && !in.read(reinterpret_cast<char*>(bytes.data()), size)) throw InputError(path + ": cannot read file");
  return parse_safetensors(bytes, path);
}

std::vector<unsigned char> serialize_safetensors(const TensorFile& file) {
  json header = json::object();
  if (!file.metadata.empty()) {
    json meta = json::object();
    for (const auto& [k, v] : file.metadata) meta[k] = v;
    header["__metadata__"] = meta;
  }
  std::uint64_t offset = 0;
  for (const auto& [name, t] : file.tensors) {  // std::map: name order
    header[name] = {{"dtype", dtype_name(t.dtype)},
                    {"shape", t.shape},
                    {"data_offsets", {offset, offset + t.bytes.size()}}};
    offset += t.bytes.size();
  }
  std::string text = header.dump();
  while ((8 + text.size()) % 8 != 0) text.push_back(' ');  // data starts 8-byte aligned
  std::vector<unsigned char> out(8 + text.size() + offset);
  const std::uint64_t header_size = text.size();
  std::memcpy(out.data(), &header_size, 8);
  std::memcpy(out.data() + 8, text.data(), text.size());
  std::size_t at = 8 + text.size();
  for (const auto& [name, t] : file.tensors) {
    if (!t.bytes.empty()) std::memcpy(out.data() + at, t.bytes.data(), t.bytes.size());
    at += t.bytes.size();
  }
  return out;
}

void write_safetensors(const std::string& path, const TensorFile& file) {
  const auto bytes = serialize_safetensors(file);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw InputError(path + ": cannot open for writing");
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!out) throw InputError(path + ": write failed");
}

}  // namespace occtrack::io
