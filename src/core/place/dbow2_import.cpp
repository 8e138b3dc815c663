#include "binloop/place/dbow2_import.h"

#include <cstdlib>
#include <fstream>
#include <sstream>

#include <opencv2/core.hpp>

#include "binloop/io/data_error.h"

namespace binloop {

namespace {

Weighting weightingFromDbow2(int w, const std::string& path) {
  if (w < 0 || w > 3) throw PlaceError(path + ": unknown DBoW2 weighting type " + std::to_string(w));
  return static_cast<Weighting>(w);  // DBoW2: TF_IDF 0, TF 1, IDF 2, BINARY 3 — the same order as ours
}

void checkScoring(int s, const std::string& path) {
  // binloop scores hbow with DBoW2's L1 score (scoring type 0), as ORB-SLAM2 does.
  if (s != 0)
    throw PlaceError(path + ": DBoW2 scoring type " + std::to_string(s) + " is not supported (only L1, 0)");
}

// Parses 32 decimal byte values; `rest` (optional) receives where parsing stopped.
Desc256 parseDescriptorBytes(const char* s, const std::string& where, char** rest = nullptr) {
  uint8_t bytes[32];
  char* end = nullptr;
  for (int i = 0; i < 32; ++i) {
    const long v = std::strtol(s, &end, 10);
    if (end == s || v < 0 || v > 255) {
      throw PlaceError(where + ": descriptor needs 32 byte values (0-255), found " + std::to_string(i) +
                       " (is this a 256-bit ORB vocabulary?)");
    }
    bytes[i] = static_cast<uint8_t>(v);
    s = end;
  }
  if (rest) *rest = end;
  return descriptorFromBytes(bytes);
}

}  // namespace

VocabularyTree importDbow2(const std::string& path) {
  const bool text = path.size() >= 4 && path.compare(path.size() - 4, 4, ".txt") == 0;
  return text ? importDbow2Text(path) : importDbow2Yaml(path);
}

VocabularyTree importDbow2Yaml(const std::string& path) {
  cv::FileStorage fs;
  try {
    if (!fs.open(path, cv::FileStorage::READ)) throw PlaceError(path + ": cannot open DBoW2 vocabulary");
  } catch (const cv::Exception& e) {
    throw PlaceError(path + ": not a readable OpenCV YAML/XML vocabulary (" + e.msg + ")");
  }
  const cv::FileNode voc = fs["vocabulary"];
  if (voc.empty()) throw PlaceError(path + ": no 'vocabulary' node (not a DBoW2 vocabulary)");
  const int k = static_cast<int>(voc["k"]), levels = static_cast<int>(voc["L"]);
  checkScoring(static_cast<int>(voc["scoringType"]), path);
  const Weighting w = weightingFromDbow2(static_cast<int>(voc["weightingType"]), path);
  const cv::FileNode nodes = voc["nodes"], words = voc["words"];
  if (nodes.empty() || words.empty()) throw PlaceError(path + ": vocabulary has no nodes or no words");
  std::vector<VocabularyTree::InputNode> in(nodes.size() + 1, {0, Desc256{}, false, 0.f});
  for (const auto& n : nodes) {
    const int id = static_cast<int>(n["nodeId"]);
    if (id <= 0 || id >= static_cast<int>(in.size())) {
      throw PlaceError(path + ": node id " + std::to_string(id) + " out of range 1.." +
                       std::to_string(in.size() - 1));
    }
    in[id].parent = static_cast<uint32_t>(static_cast<int>(n["parentId"]));
    in[id].weight = static_cast<float>(static_cast<double>(n["weight"]));
    const std::string desc = static_cast<std::string>(n["descriptor"]);
    in[id].descriptor = parseDescriptorBytes(desc.c_str(), path + ": node " + std::to_string(id));
  }
  for (const auto& wd : words) {
    const int node = static_cast<int>(wd["nodeId"]);
    if (node <= 0 || node >= static_cast<int>(in.size()))
      throw PlaceError(path + ": word refers to node " + std::to_string(node) + ", which does not exist");
    in[node].is_leaf = true;
  }
  return VocabularyTree::fromNodes(k, levels, w, in);
}

VocabularyTree importDbow2Text(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw PlaceError(path + ": cannot open DBoW2 text vocabulary");
  std::string line;
  if (!std::getline(f, line)) throw PlaceError(path + ": empty file");
  std::istringstream head(line);
  int k = 0, levels = 0, scoring = -1, weighting = -1;
  if (!(head >> k >> levels >> scoring >> weighting) || k < 2 || levels < 1)
    throw PlaceError(dataError(path, 1, "expected 'k L scoring weighting', found '" + line + "'").what());
  checkScoring(scoring, path);
  const Weighting w = weightingFromDbow2(weighting, path);
  std::vector<VocabularyTree::InputNode> in{{0, Desc256{}, false, 0.f}};
  in.reserve(1100000);
  int line_no = 1;
  while (std::getline(f, line)) {
    ++line_no;
    if (line.empty() || line == "\r") continue;
    const std::string where = dataError(path, line_no, "").what();
    char* s = line.data();
    char* end = nullptr;
    const long parent = std::strtol(s, &end, 10);
    if (end == s) throw PlaceError(where + "expected 'parent is_leaf <32 bytes> weight'");
    s = end;
    const long leaf = std::strtol(s, &end, 10);
    if (end == s || (leaf != 0 && leaf != 1)) throw PlaceError(where + "is_leaf must be 0 or 1");
    s = end;
    VocabularyTree::InputNode n{static_cast<uint32_t>(parent), parseDescriptorBytes(s, where + "node", &s),
                                leaf == 1, 0.f};
    const double weight = std::strtod(s, &end);
    if (end == s) throw PlaceError(where + "missing the node weight after the 32 descriptor bytes");
    n.weight = static_cast<float>(weight);
    if (parent < 0 || static_cast<size_t>(parent) >= in.size())
      throw PlaceError(where + "parent " + std::to_string(parent) + " is not an earlier node");
    in.push_back(n);
  }
  return VocabularyTree::fromNodes(k, levels, w, in);
}

}  // namespace binloop
