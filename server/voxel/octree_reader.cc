#include "voxel/octree_reader.h"

#include <octomap/AbstractOcTree.h>
#include <octomap/OcTree.h>

#include <array>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <utility>

namespace mapd::voxel {
namespace {

constexpr std::string_view kBinaryMagic = "# Octomap OcTree binary file";
constexpr std::string_view kFullMagic = "# Octomap OcTree file";
constexpr std::size_t kMaxHeaderBytes = 64 * 1024;
constexpr double kMaxResolution = 1000.0;  // metres; beyond this keys overflow doubles' sense
constexpr std::size_t kFullNodeBytes = sizeof(float) + 1;  // log-odds + child mask

std::string Str(std::uint64_t v) { return std::to_string(v); }

// The header fields, each present at most once.
struct Header {
  OctreeFormat format = OctreeFormat::kBinary;
  std::string id;
  bool has_size = false;
  std::uint64_t size = 0;
  bool has_res = false;
  double resolution = 0.0;
  std::size_t data_offset = 0;
};

bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

std::string_view Trim(std::string_view s) {
  while (!s.empty() && IsSpace(s.front())) s.remove_prefix(1);
  while (!s.empty() && IsSpace(s.back())) s.remove_suffix(1);
  return s;
}

// Splits off the first whitespace-separated token of `s`.
std::string_view NextToken(std::string_view& s) {
  s = Trim(s);
  std::size_t end = 0;
  while (end < s.size() && !IsSpace(s[end])) ++end;
  std::string_view token = s.substr(0, end);
  s.remove_prefix(end);
  s = Trim(s);
  return token;
}

std::string Printable(std::string_view s) {
  std::string out;
  for (char c : s.substr(0, 40)) {
    out += (c >= 0x20 && c < 0x7f) ? c : '?';
  }
  if (s.size() > 40) out += "...";
  return out;
}

Status ParseResolution(std::string_view value, double* resolution) {
  double res = 0.0;
  const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), res);
  if (ec != std::errc() || end != value.data() + value.size()) {
    return Status::InvalidArgument("header: resolution '" + Printable(value) + "' is not a number");
  }
  if (std::isnan(res)) return Status::InvalidArgument("header: resolution is NaN");
  if (std::isinf(res)) return Status::InvalidArgument("header: resolution is infinite");
  if (res <= 0.0) {
    return Status::InvalidArgument("header: resolution " + std::string(value) + " is not positive");
  }
  if (res > kMaxResolution) {
    return Status::InvalidArgument("header: resolution " + std::string(value) +
                                   " m is implausibly large (limit 1000 m)");
  }
  *resolution = res;
  return Status::Ok();
}

Status ParseSize(std::string_view value, std::uint64_t* size) {
  std::uint64_t v = 0;
  const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), v);
  if (value.empty() || value.front() == '-' || ec != std::errc() ||
      end != value.data() + value.size() || v > std::numeric_limits<std::uint32_t>::max()) {
    return Status::InvalidArgument("header: size '" + Printable(value) +
                                   "' is not an unsigned 32-bit integer");
  }
  *size = v;
  return Status::Ok();
}

// OctoMap's header grammar (AbstractOcTree::readHeader), but strict: one
// `keyword value` per line, comments start with '#', unknown keywords and
// repeated fields are errors, and the header ends at the line "data".
StatusOr<Header> ParseHeader(std::string_view bytes) {
  if (bytes.empty()) return Status::InvalidArgument("empty input: no octree header");
  Header header;
  std::size_t pos = 0;
  bool first = true;
  while (true) {
    const std::size_t eol = bytes.find('\n', pos);
    if (eol == std::string_view::npos || eol >= kMaxHeaderBytes) {
      if (first) {
        return Status::InvalidArgument("not an octree file: no header line in the first " +
                                       Str(std::min(bytes.size(), kMaxHeaderBytes)) + " bytes");
      }
      return Status::InvalidArgument("header: no 'data' line in the first " +
                                     Str(std::min(bytes.size(), kMaxHeaderBytes)) + " bytes");
    }
    std::string_view line = bytes.substr(pos, eol - pos);
    pos = eol + 1;
    if (first) {
      first = false;
      // OctoMap compares the line's prefix with the magic string.
      if (line.substr(0, kBinaryMagic.size()) == kBinaryMagic) {
        header.format = OctreeFormat::kBinary;
      } else if (line.substr(0, kFullMagic.size()) == kFullMagic) {
        header.format = OctreeFormat::kFull;
      } else {
        return Status::InvalidArgument("not an octree file: first line '" + Printable(line) +
                                       "' is neither '" + std::string(kBinaryMagic) + "' nor '" +
                                       std::string(kFullMagic) + "'");
      }
      continue;
    }
    line = Trim(line);
    if (line.empty() || line.front() == '#') continue;
    const std::string_view keyword = NextToken(line);
    if (keyword == "data") {
      if (!line.empty()) {
        return Status::InvalidArgument("header: unexpected text after 'data': '" + Printable(line) +
                                       "'");
      }
      header.data_offset = pos;
      break;
    }
    const std::string_view value = NextToken(line);
    if (value.empty() || !line.empty()) {
      return Status::InvalidArgument("header: '" + Printable(keyword) +
                                     "' needs exactly one value");
    }
    if (keyword == "id") {
      if (!header.id.empty()) return Status::InvalidArgument("header: 'id' given twice");
      header.id = std::string(value);
    } else if (keyword == "size") {
      if (header.has_size) return Status::InvalidArgument("header: 'size' given twice");
      MAPD_RETURN_IF_ERROR(ParseSize(value, &header.size));
      header.has_size = true;
    } else if (keyword == "res") {
      if (header.has_res) return Status::InvalidArgument("header: 'res' given twice");
      MAPD_RETURN_IF_ERROR(ParseResolution(value, &header.resolution));
      header.has_res = true;
    } else {
      return Status::InvalidArgument("header: unknown keyword '" + Printable(keyword) + "'");
    }
  }
  if (header.id.empty()) return Status::InvalidArgument("header: no 'id' line");
  if (header.id != "OcTree") {
    return Status::InvalidArgument("header: id '" + Printable(header.id) +
                                   "' is not supported (only OcTree)");
  }
  if (!header.has_size) return Status::InvalidArgument("header: no 'size' line");
  if (!header.has_res) return Status::InvalidArgument("header: no 'res' line");
  return header;
}

Status Truncated(std::size_t have, std::uint64_t need) {
  return Status::InvalidArgument("truncated after " + Str(have) + " of at least " + Str(need) +
                                 " bytes");
}

Status DeeperThanMax(std::size_t offset) {
  return Status::InvalidArgument("tree deeper than " + Str(kOctreeMaxDepth) +
                                 " levels (node record at byte " + Str(offset) + ")");
}

Status TooManyNodes(std::uint64_t size, std::size_t offset) {
  return Status::InvalidArgument("more nodes than the header's size " + Str(size) + " (at byte " +
                                 Str(offset) + ")");
}

// One open inner node of the depth-first walk: its depth and the children
// whose records are still to come (bit i = child i). Depth is bounded by
// kOctreeMaxDepth, so the stack is a fixed array.
struct Frame {
  int depth = 0;
  unsigned pending = 0;
  std::uint32_t key[3] = {0, 0, 0};  // the node's cube's smallest OctoMap key per axis
};
using Stack = std::array<Frame, kOctreeMaxDepth + 1>;

// Takes the next pending child of the deepest open node, popping finished
// nodes; returns false when the walk is complete.
// The smallest key of child `i` of a node at `depth` whose smallest key is
// `key`: bit 0/1/2 of i selects the upper half in x/y/z (OctoMap's
// computeChildKey).
void ChildKey(const std::uint32_t key[3], int depth, int i, std::uint32_t out[3]) {
  const std::uint32_t half = std::uint32_t{1} << (kOctreeMaxDepth - depth - 1);
  for (int a = 0; a < 3; ++a) out[a] = key[a] + ((i >> a) & 1 ? half : 0);
}

// Counts a leaf at `depth` with smallest key `key` into the summary; false when
// the occupied voxels exceed `max_occupied` (0 = no limit).
bool AddLeaf(bool occupied, int depth, const std::uint32_t key[3], std::uint64_t max_occupied,
             OctreeSummary* s) {
  const int level = kOctreeMaxDepth - depth;
  const std::uint64_t voxels = std::uint64_t{1} << (3 * level);
  if (!occupied) {
    s->free_voxels =
        s->free_voxels + voxels < s->free_voxels ? ~std::uint64_t{0} : s->free_voxels + voxels;
    return true;
  }
  const bool first = s->occupied_voxels == 0;
  s->occupied_voxels += voxels;  // <= 2^62 + 2^48 before the check: no overflow
  for (int a = 0; a < 3; ++a) {
    const std::int32_t lo = static_cast<std::int32_t>(key[a]) - 32768;
    const std::int32_t hi = lo + (std::int32_t{1} << level) - 1;
    s->occupied_min_key[a] = first ? lo : std::min(s->occupied_min_key[a], lo);
    s->occupied_max_key[a] = first ? hi : std::max(s->occupied_max_key[a], hi);
  }
  return max_occupied == 0 || s->occupied_voxels <= max_occupied;
}

Status TooManyVoxels(std::uint64_t max_occupied, std::size_t offset) {
  return Status::ResourceExhausted("the tree expands to more than " + Str(max_occupied) +
                                   " occupied voxels at the finest resolution (at byte " +
                                   Str(offset) + ")");
}

bool NextChild(Stack& stack, int& top, int* child_depth, std::uint32_t child_key[3]) {
  while (top >= 0) {
    Frame& frame = stack[top];
    if (frame.pending != 0) {
      const int i = __builtin_ctz(frame.pending);
      frame.pending &= frame.pending - 1;  // children are read in order 0..7
      *child_depth = frame.depth + 1;
      ChildKey(frame.key, frame.depth, i, child_key);
      return true;
    }
    --top;
  }
  return false;
}

// Pending records below the open nodes (each needs at least `record` bytes).
std::uint64_t PendingRecords(const Stack& stack, int top) {
  std::uint64_t n = 0;
  for (int i = 0; i <= top; ++i) n += static_cast<unsigned>(__builtin_popcount(stack[i].pending));
  return n;
}

// After the last node: every byte consumed, and as many nodes as the header said.
Status CheckTreeEnd(std::string_view bytes, std::size_t pos, std::uint64_t nodes,
                    const Header& header) {
  if (pos != bytes.size()) {
    return Status::InvalidArgument(Str(bytes.size() - pos) + " trailing bytes after the tree (" +
                                   "tree ends at byte " + Str(pos) + " of " + Str(bytes.size()) +
                                   ")");
  }
  if (nodes != header.size) {
    return Status::InvalidArgument("header says size " + Str(header.size) + " but the tree has " +
                                   Str(nodes) + " nodes");
  }
  return Status::Ok();
}

// A tree of size 0 has no node records: nothing may follow its header.
Status CheckEmptyTreeEnds(std::string_view bytes, std::size_t pos) {
  if (pos == bytes.size()) return Status::Ok();
  return Status::InvalidArgument(Str(bytes.size() - pos) +
                                 " trailing bytes after an empty tree (size 0)");
}

// .bt (OccupancyOcTreeBase::readBinaryNode): each inner node is 2 bytes, two
// bits per child i (bits 2i, 2i+1 of byte i/4): 00 unknown (no child), 10 free
// leaf, 01 occupied leaf, 11 inner node whose record follows depth-first in
// child order. Every non-00 code creates a node; the root is one more.
Status ValidateBinaryData(std::string_view bytes, const Header& header, std::uint64_t max_occupied,
                          OctreeSummary* summary) {
  std::size_t pos = header.data_offset;
  if (header.size == 0) return CheckEmptyTreeEnds(bytes, pos);
  Stack stack;
  int top = -1;
  std::uint64_t nodes = 1;           // the root
  int depth = 0;                     // depth of the node whose record comes next
  std::uint32_t key[3] = {0, 0, 0};  // its smallest key
  int max_depth = 0;
  while (true) {
    if (depth >= kOctreeMaxDepth) return DeeperThanMax(pos);
    if (bytes.size() - pos < 2) {
      return Truncated(bytes.size(), pos + 2 + 2 * PendingRecords(stack, top));
    }
    const auto lo = static_cast<unsigned char>(bytes[pos]);
    const auto hi = static_cast<unsigned char>(bytes[pos + 1]);
    const unsigned codes = lo | (hi << 8);  // child i: bits 2i, 2i+1
    unsigned inner = 0;
    int created = 0;
    for (int i = 0; i < 8; ++i) {
      const unsigned code = (codes >> (2 * i)) & 3u;
      if (code != 0) ++created;
      if (code == 3) inner |= 1u << i;
      if (code == 1 || code == 2) {  // 1: free leaf, 2: occupied leaf
        std::uint32_t child[3];
        ChildKey(key, depth, i, child);
        if (depth + 1 <= kOctreeMaxDepth &&
            !AddLeaf(code == 2, depth + 1, child, max_occupied, summary)) {
          return TooManyVoxels(max_occupied, pos);
        }
      }
    }
    // A root without children is one occupied leaf (OctoMap sets inner nodes
    // to occupied before reading their children).
    if (created == 0 && depth == 0 && !AddLeaf(true, 0, key, max_occupied, summary)) {
      return TooManyVoxels(max_occupied, pos);
    }
    if (created == 0 && depth > 0) {
      return Status::InvalidArgument("inner node at byte " + Str(pos) +
                                     " has no children (OctoMap never writes this)");
    }
    if (inner != 0 && depth + 1 >= kOctreeMaxDepth) return DeeperThanMax(pos);
    pos += 2;
    nodes += static_cast<std::uint64_t>(created);
    if (nodes > header.size) return TooManyNodes(header.size, pos);
    if (created > 0) max_depth = std::max(max_depth, depth + 1);
    stack[++top] = Frame{depth, inner, {key[0], key[1], key[2]}};
    if (!NextChild(stack, top, &depth, key)) break;
  }
  MAPD_RETURN_IF_ERROR(CheckTreeEnd(bytes, pos, nodes, header));
  summary->max_depth = max_depth;
  return Status::Ok();
}

// .ot (OcTreeBaseImpl::readNodesRecurs + OcTreeDataNode<float>::readData):
// each node is its float log-odds value (host byte order) and a byte whose bit i
// says child i follows, depth-first in child order. Exactly 5 bytes per node.
Status ValidateFullData(std::string_view bytes, const Header& header, std::uint64_t max_occupied,
                        OctreeSummary* summary) {
  std::size_t pos = header.data_offset;
  const std::uint64_t expected = pos + header.size * kFullNodeBytes;
  if (bytes.size() < expected) return Truncated(bytes.size(), expected);
  if (header.size == 0) return CheckEmptyTreeEnds(bytes, pos);
  Stack stack;
  int top = -1;
  std::uint64_t nodes = 0;
  int depth = 0;
  std::uint32_t key[3] = {0, 0, 0};
  int max_depth = 0;
  while (true) {
    if (bytes.size() - pos < kFullNodeBytes) {
      return Truncated(bytes.size(), pos + kFullNodeBytes * (1 + PendingRecords(stack, top)));
    }
    if (++nodes > header.size) return TooManyNodes(header.size, pos);
    float log_odds = 0.0f;
    std::memcpy(&log_odds, bytes.data() + pos, sizeof(log_odds));
    if (!std::isfinite(log_odds)) {
      return Status::InvalidArgument("node " + Str(nodes - 1) + " at byte " + Str(pos) +
                                     " has a non-finite log-odds value");
    }
    const auto mask = static_cast<unsigned char>(bytes[pos + sizeof(float)]);
    if (mask != 0 && depth >= kOctreeMaxDepth) return DeeperThanMax(pos);
    max_depth = std::max(max_depth, depth);
    // A leaf: occupied as OcTree::isNodeOccupied says with the default
    // threshold (probability 0.5, log-odds 0).
    if (mask == 0 && !AddLeaf(log_odds >= 0.0f, depth, key, max_occupied, summary)) {
      return TooManyVoxels(max_occupied, pos);
    }
    pos += kFullNodeBytes;
    stack[++top] = Frame{depth, mask, {key[0], key[1], key[2]}};
    if (!NextChild(stack, top, &depth, key)) break;
  }
  MAPD_RETURN_IF_ERROR(CheckTreeEnd(bytes, pos, nodes, header));
  summary->max_depth = max_depth;
  return Status::Ok();
}

}  // namespace

StatusOr<OctreeSummary> ValidateOctree(std::string_view bytes, const OctreeReadLimits& limits) {
  if (bytes.size() > limits.max_bytes) {
    return Status::ResourceExhausted("input is " + Str(bytes.size()) + " bytes; the limit is " +
                                     Str(limits.max_bytes));
  }
  StatusOr<Header> header = ParseHeader(bytes);
  if (!header.ok()) return header.status();
  const std::uint64_t max_nodes = limits.max_bytes / kOctreeBytesPerNode;
  if (header->size > max_nodes) {
    return Status::ResourceExhausted("header claims " + Str(header->size) +
                                     " nodes; the limit is " + Str(max_nodes) + " (max_bytes " +
                                     Str(limits.max_bytes) + ")");
  }
  OctreeSummary summary;
  summary.format = header->format;
  summary.resolution = header->resolution;
  summary.num_nodes = header->size;
  summary.data_offset = header->data_offset;
  if (header->format == OctreeFormat::kBinary) {
    MAPD_RETURN_IF_ERROR(ValidateBinaryData(bytes, *header, limits.max_occupied_voxels, &summary));
  } else {
    MAPD_RETURN_IF_ERROR(ValidateFullData(bytes, *header, limits.max_occupied_voxels, &summary));
  }
  return summary;
}

void OcTreeDeleter::operator()(octomap::OcTree* tree) const { delete tree; }

StatusOr<OcTreePtr> ReadOctree(std::string_view bytes, const OctreeReadLimits& limits) {
  StatusOr<OctreeSummary> summary = ValidateOctree(bytes, limits);
  if (!summary.ok()) return summary.status();
  if (summary->num_nodes == 0) {
    return OcTreePtr(new octomap::OcTree(summary->resolution));
  }
  // Only the validated tree bytes go to OctoMap, through its data readers
  // (readBinaryData, readData): its header parsers (readBinary,
  // AbstractOcTree::read) are lenient and print "Reading octree type ..." on
  // stdout/stderr, which would land in mapd's logfmt log. The header values
  // are the ones we validated.
  const bool binary = summary->format == OctreeFormat::kBinary;
  const std::string_view data = bytes.substr(summary->data_offset);
  std::istringstream in(std::string(data), std::ios_base::in | std::ios_base::binary);
  OcTreePtr tree(new octomap::OcTree(summary->resolution));
  if (binary) {
    tree->readBinaryData(in);
  } else {
    tree->readData(in);
  }
  if (in.fail() || static_cast<std::size_t>(in.tellg()) != data.size() ||
      tree->size() != summary->num_nodes || tree->getResolution() != summary->resolution) {
    return Status::Internal("OctoMap read a validated tree differently (" + Str(tree->size()) +
                            " of " + Str(summary->num_nodes) + " nodes)");
  }
  return tree;
}

StatusOr<OcTreePtr> ReadOctreeFile(const std::string& path, const OctreeReadLimits& limits) {
  std::ifstream file(path, std::ios_base::in | std::ios_base::binary);
  if (!file.is_open()) return Status::NotFound("cannot open octree file " + path);
  file.seekg(0, std::ios_base::end);
  const std::streamoff length = file.tellg();
  if (length < 0) return Status::InvalidArgument("cannot determine the size of " + path);
  if (static_cast<std::uint64_t>(length) > limits.max_bytes) {
    return Status::ResourceExhausted(path + " is " + Str(static_cast<std::uint64_t>(length)) +
                                     " bytes; the limit is " + Str(limits.max_bytes));
  }
  file.seekg(0, std::ios_base::beg);
  std::string bytes(static_cast<std::size_t>(length), '\0');
  if (!file.read(bytes.data(), length)) return Status::InvalidArgument("cannot read " + path);
  StatusOr<OcTreePtr> tree = ReadOctree(bytes, limits);
  if (!tree.ok()) return Status(tree.status().code(), path + ": " + tree.status().message());
  return tree;
}

}  // namespace mapd::voxel
