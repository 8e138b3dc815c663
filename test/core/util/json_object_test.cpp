// The tools' JSON writer: field order kept, strings escaped, numbers as before (6 significant digits), nested
// objects on one line or one field a line.
#include "binloop/util/json_object.h"

#include <gtest/gtest.h>

#include <cmath>

namespace binloop {
namespace {

TEST(JsonObject, WritesFieldsInOrderWithNestedObjects) {
  JsonObject status;
  status.add("accepted", 2).add("held", 1u);
  JsonObject settings(true);
  settings.addRaw("orb.features", "2000");
  JsonObject o;
  o.add("sequence", "/data/06").add("frames", 1101ul).add("wall_s", 12.345678).add("lockstep", false);
  o.add("loops_by_status", status).add("settings", settings);
  EXPECT_EQ(o.str(),
            "{\n"
            "  \"sequence\": \"/data/06\",\n"
            "  \"frames\": 1101,\n"
            "  \"wall_s\": 12.3457,\n"
            "  \"lockstep\": false,\n"
            "  \"loops_by_status\": {\"accepted\": 2, \"held\": 1},\n"
            "  \"settings\": {\n"
            "    \"orb.features\": 2000\n"
            "  }\n"
            "}\n");
}

TEST(JsonObject, EscapesStringsAndWritesNullForNonFiniteNumbers) {
  JsonObject o;
  o.add("path", "a \"b\"\\c\nd\x01").add("ate", std::nan("")).add("empty", JsonObject());
  EXPECT_EQ(o.str(),
            "{\n  \"path\": \"a \\\"b\\\"\\\\c\\nd\\u0001\",\n  \"ate\": null,\n  \"empty\": {}\n}\n");
}

}  // namespace
}  // namespace binloop
