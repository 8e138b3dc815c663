#pragma once
// Reads back what util/json_object.h writes (run's and record-run's summary.json, the benches' files): the
// top-level fields of one JSON object, by key. A string field gives its text unescaped; any other value
// (number, true, false, null, a nested object or array) its JSON as written.
#include <map>
#include <string>

namespace binloop {

using JsonFields = std::map<std::string, std::string>;

/// Throws DataError naming `source` and the offset for text that is not one JSON object (a repeated key
/// included: the file would be ambiguous).
JsonFields readJsonFields(const std::string& text, const std::string& source);

/// The field as a number; NaN when it is absent, null or not a number.
double jsonNumber(const JsonFields& fields, const std::string& key);

}  // namespace binloop
