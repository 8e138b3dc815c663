#pragma once
// Reads DBoW2 vocabularies: DBoW2's OpenCV-storage format (.yml, .yml.gz, .xml) and ORB-SLAM2's text
// format (ORBvoc.txt: a "k L scoring weighting" line, then one "parent is_leaf 32 bytes weight" line per
// node). Errors name the file and the line or node at fault.
#include <string>

#include "binloop/place/vocabulary_tree.h"

namespace binloop {

/// Chooses the parser by extension (.txt → text, otherwise OpenCV storage).
VocabularyTree importDbow2(const std::string& path);
VocabularyTree importDbow2Yaml(const std::string& path);
VocabularyTree importDbow2Text(const std::string& path);

}  // namespace binloop
