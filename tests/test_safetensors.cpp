// safetensors reader and writer: round trip, the byte layout of the format, and refusals that name the problem.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "occtrack/io/error.hpp"
#include "occtrack/io/safetensors.hpp"

namespace occtrack::io {
namespace {

std::string message_of(const std::vector<unsigned char>& bytes) {
  try {
    parse_safetensors(bytes, "file.safetensors");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

std::vector<unsigned char> with_header(const std::string& header, std::size_t data_bytes) {
  std::vector<unsigned char> out(8 + header.size() + data_bytes, 0);
  const std::uint64_t n = header.size();
  std::memcpy(out.data(), &n, 8);
  std::memcpy(out.data() + 8, header.data(), header.size());
  return out;
}

TEST(Safetensors, RoundTripKeepsValuesShapesDtypesAndMetadata) {
  TensorFile file;
  file.metadata["format"] = "occtrack.test.v1";
  file.metadata["network"] = R"({"hidden": 8})";
  file.put("a.weight", {2, 3}, std::vector<float>{1, 2, 3, 4, 5, 6.5f});
  file.put("b", {3}, std::vector<double>{0.1, -2e-300, 1e300});
  file.put("episode", {2}, std::vector<std::int32_t>{7, -1});
  file.put("big", {1}, std::vector<std::int64_t>{1LL << 40});
  file.put("empty", {0, 4}, std::vector<float>{});
  const auto bytes = serialize_safetensors(file);
  std::uint64_t header = 0;
  std::memcpy(&header, bytes.data(), 8);
  EXPECT_EQ((8 + header) % 8, 0u) << "data must start 8-byte aligned";

  const TensorFile back = parse_safetensors(bytes, "x");
  EXPECT_EQ(back.metadata, file.metadata);
  ASSERT_EQ(back.tensors.size(), 5u);
  EXPECT_EQ(back.at("a.weight", {2, 3}).as_float(), (std::vector<float>{1, 2, 3, 4, 5, 6.5f}));
  EXPECT_EQ(back.at("b").dtype, DType::F64);
  EXPECT_EQ(back.at("b").as_double(), (std::vector<double>{0.1, -2e-300, 1e300}));
  EXPECT_EQ(back.at("episode").as_double(), (std::vector<double>{7, -1}));
  EXPECT_EQ(back.at("big").as_double()[0], double(1LL << 40));
  EXPECT_EQ(back.at("empty").numel(), 0);
}

TEST(Safetensors, LayoutIsTheFormatsHeaderPlusRawLittleEndianData) {
  TensorFile file;
  file.put("x", {2}, std::vector<float>{1.0f, -2.0f});
  const auto bytes = serialize_safetensors(file);
  std::uint64_t n = 0;
  std::memcpy(&n, bytes.data(), 8);
  const std::string header(reinterpret_cast<const char*>(bytes.data() + 8), n);
  EXPECT_NE(header.find(R"("x":{"data_offsets":[0,8],"dtype":"F32","shape":[2]})"), std::string::npos) << header;
  float v[2];
  std::memcpy(v, bytes.data() + 8 + n, 8);
  EXPECT_EQ(v[0], 1.0f);
  EXPECT_EQ(v[1], -2.0f);
}

TEST(Safetensors, RefusesBrokenFilesNamingWhatIsWrong) {
  EXPECT_NE(message_of({1, 2, 3}).find("fewer than the 8-byte header length"), std::string::npos);
  EXPECT_TRUE(parse_safetensors(with_header("{}", 0), "x").tensors.empty());
  auto huge = with_header("{}", 0);
  huge[6] = 1;
  EXPECT_NE(message_of(huge).find("exceeds the file"), std::string::npos);
  EXPECT_NE(message_of(with_header("{not json", 0)).find("not valid JSON"), std::string::npos);
  EXPECT_NE(message_of(with_header(R"({"w":{"dtype":"BF16","shape":[1],"data_offsets":[0,2]}})", 2))
                .find("tensor 'w' has dtype BF16"),
            std::string::npos);
  EXPECT_NE(message_of(with_header(R"({"w":{"dtype":"F32","shape":[3],"data_offsets":[0,8]}})", 8))
                .find("tensor 'w': shape [3] of F32 needs 12 bytes, data_offsets give 8"),
            std::string::npos);
  EXPECT_NE(message_of(with_header(R"({"w":{"dtype":"F32","shape":[4],"data_offsets":[0,16]}})", 8))
                .find("lie outside the data"),
            std::string::npos);
  EXPECT_NE(message_of(with_header(R"({"w":{"dtype":"F32","shape":[-1],"data_offsets":[0,4]}})", 4))
                .find("non-negative integers"),
            std::string::npos);
  EXPECT_NE(message_of(with_header(R"({"a":{"dtype":"F32","shape":[2],"data_offsets":[0,8]},)"
                                   R"("b":{"dtype":"F32","shape":[2],"data_offsets":[4,12]}})",
                                   12))
                .find("overlapping"),
            std::string::npos);
  EXPECT_NE(message_of(with_header(R"({"__metadata__":{"k":3}})", 0)).find("__metadata__.k must be a string"),
            std::string::npos);
}

TEST(Safetensors, LookupsNameTheFileAndTheTensor) {
  TensorFile file;
  file.source = "model.safetensors";
  file.put("w", {2, 2}, std::vector<float>(4, 0.f));
  try {
    file.at("v");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "model.safetensors: tensor 'v' is missing");
  }
  try {
    file.at("w", {2, 3});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "model.safetensors: tensor 'w' has shape [2, 2], expected [2, 3]");
  }
  EXPECT_THROW(file.meta("format"), InputError);
  EXPECT_THROW(file.put("bad", {3}, std::vector<float>(2)), std::invalid_argument);
  EXPECT_THROW(read_safetensors("/nonexistent/model.safetensors"), InputError);
}

}  // namespace
}  // namespace occtrack::io
