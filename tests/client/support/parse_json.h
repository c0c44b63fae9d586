// Parses JSON text into a protobuf Struct, for tests that check mapctl's
// JSON and GeoJSON output field by field.
#ifndef MAPD_TESTS_CLIENT_SUPPORT_PARSE_JSON_H_
#define MAPD_TESTS_CLIENT_SUPPORT_PARSE_JSON_H_

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <gtest/gtest.h>

#include <string>

namespace mapd::client {

// Fails the calling test (and returns an empty Struct) on invalid JSON.
inline google::protobuf::Struct ParseJson(const std::string& text) {
  google::protobuf::Struct s;
  const auto status = google::protobuf::util::JsonStringToMessage(text, &s);
  EXPECT_TRUE(status.ok()) << status.message() << "\n" << text;
  return s;
}

}  // namespace mapd::client

#endif  // MAPD_TESTS_CLIENT_SUPPORT_PARSE_JSON_H_
