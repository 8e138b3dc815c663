// Reading back the tools' JSON: every field JsonObject writes comes back by key, strings unescaped, other
// values as written; text that is not one object is an error naming the file.
#include "binloop/io/json_fields.h"

#include <gtest/gtest.h>

#include <cmath>

#include "binloop/io/data_error.h"
#include "binloop/util/json_object.h"
#include "support/test_support.h"

namespace binloop {
namespace {

TEST(JsonFields, ReadsBackWhatJsonObjectWrites) {
  JsonObject nested;
  nested.add("accepted", 2).add("note", "a \"quoted\" } word");
  JsonObject o;
  o.add("sequence", "/data/06 \"odd\"\\name\n\ttab").add("frames", 1101ul).add("wall_s", 12.345678);
  o.add("lockstep", false).add("ate_m", NAN).add("by_status", nested).addRaw("list", "[1, \"]\", 3]");
  o.add("detector", "hmvlad");
  const JsonFields f = readJsonFields(o.str(), "summary.json");
  EXPECT_EQ(f.size(), 8u);
  EXPECT_EQ(f.at("sequence"), "/data/06 \"odd\"\\name\n\ttab");
  EXPECT_EQ(f.at("frames"), "1101");
  EXPECT_EQ(jsonNumber(f, "frames"), 1101);
  EXPECT_NEAR(jsonNumber(f, "wall_s"), 12.3457, 1e-9);
  EXPECT_EQ(f.at("lockstep"), "false");
  EXPECT_EQ(f.at("ate_m"), "null");
  EXPECT_TRUE(std::isnan(jsonNumber(f, "ate_m")));
  EXPECT_TRUE(std::isnan(jsonNumber(f, "missing")));
  EXPECT_TRUE(std::isnan(jsonNumber(f, "detector")));
  EXPECT_EQ(f.at("by_status"), nested.str(1));
  EXPECT_EQ(f.at("list"), "[1, \"]\", 3]");
  EXPECT_EQ(f.at("detector"), "hmvlad");
  // A key that is also some field's value is still found as the key.
  JsonObject tricky;
  tricky.add("a", "detector").add("detector", "none");
  EXPECT_EQ(readJsonFields(tricky.str(), "x").at("detector"), "none");
  EXPECT_EQ(readJsonFields("{\"u\": \"\\u00e9\\u0041\"}", "x").at("u"),
            "\xc3\xa9"
            "A");
  EXPECT_TRUE(readJsonFields(" { } ", "x").empty());
}

TEST(JsonFields, RefusesWhatIsNotOneObject) {
  EXPECT_THROW_WITH(readJsonFields("", "out/summary.json"), DataError,
                    "out/summary.json: not the JSON object expected: '{' wanted at offset 0");
  EXPECT_THROW_WITH(readJsonFields("{\"frames\": 12", "s.json"), DataError, "'}' wanted at offset 13");
  EXPECT_THROW_WITH(readJsonFields("{\"frames\" 12}", "s.json"), DataError, "':' wanted");
  EXPECT_THROW_WITH(readJsonFields("{\"a\": \"open}", "s.json"), DataError, "a closing quote");
  EXPECT_THROW_WITH(readJsonFields("{\"a\": {\"b\": 1}", "s.json"), DataError, "'}' wanted");
  EXPECT_THROW_WITH(readJsonFields("{\"a\": {\"b\": [1}", "s.json"), DataError, "a closing bracket");
  EXPECT_THROW_WITH(readJsonFields("{\"a\": 1, \"a\": 2}", "s.json"), DataError, "no repeated field name");
  EXPECT_THROW_WITH(readJsonFields("{\"a\": }", "s.json"), DataError, "a value");
  EXPECT_THROW_WITH(readJsonFields("{a: 1}", "s.json"), DataError, "a field name in quotes");
  EXPECT_THROW_WITH(readJsonFields("{} {}", "s.json"), DataError, "nothing after the object");
}

}  // namespace
}  // namespace binloop
