#include "voxel/support/ply_reader.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>

namespace mapd::testing {
namespace {

// Byte size of a PLY scalar type name, 0 if unknown.
int ScalarSize(const std::string& type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "int32" || type == "uint32") return 4;
  if (type == "float" || type == "float32") return 4;
  if (type == "double" || type == "float64") return 8;
  return 0;
}

struct Property {
  std::string name;
  std::string type;
  int size = 0;
};

struct Element {
  std::string name;
  int64_t count = 0;
  std::vector<Property> properties;
  bool has_list = false;
};

double ReadBinaryScalar(const char* p, const std::string& type) {
  if (type == "float" || type == "float32") {
    float f;
    std::memcpy(&f, p, 4);
    return f;
  }
  double d;
  std::memcpy(&d, p, 8);
  return d;
}

}  // namespace

StatusOr<std::vector<Eigen::Vector3d>> ReadPlyVertices(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::NotFound("cannot open " + path);
  std::string line;
  if (!std::getline(in, line) || line.rfind("ply", 0) != 0) {
    return Status::InvalidArgument(path + ": not a PLY file");
  }
  std::string format;
  std::vector<Element> elements;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string key;
    ls >> key;
    if (key == "format") {
      ls >> format;
    } else if (key == "element") {
      Element e;
      ls >> e.name >> e.count;
      elements.push_back(e);
    } else if (key == "property") {
      if (elements.empty()) return Status::InvalidArgument(path + ": property before element");
      Property p;
      ls >> p.type;
      if (p.type == "list") {
        elements.back().has_list = true;
        std::string count_type, item_type;
        ls >> count_type >> item_type >> p.name;
      } else {
        ls >> p.name;
        p.size = ScalarSize(p.type);
        if (p.size == 0) return Status::InvalidArgument(path + ": unknown type " + p.type);
      }
      elements.back().properties.push_back(p);
    } else if (key == "end_header") {
      break;
    }
  }
  if (format != "ascii" && format != "binary_little_endian") {
    return Status::Unimplemented(path + ": PLY format '" + format + "' not supported");
  }
  // Elements before "vertex" must be skippable: no lists (their size varies).
  std::vector<Eigen::Vector3d> points;
  for (const Element& e : elements) {
    if (e.name != "vertex") {
      if (e.has_list || e.count > 0) {
        return Status::Unimplemented(path + ": element '" + e.name + "' before vertex");
      }
      continue;
    }
    int ix = -1, iy = -1, iz = -1;
    int record = 0;
    std::vector<int> offset;
    for (size_t k = 0; k < e.properties.size(); ++k) {
      const Property& p = e.properties[k];
      if (p.size == 0) return Status::Unimplemented(path + ": list property in vertex");
      offset.push_back(record);
      record += p.size;
      const bool real = p.size == 4 ? (p.type == "float" || p.type == "float32")
                                    : (p.type == "double" || p.type == "float64");
      int* slot = p.name == "x" ? &ix : p.name == "y" ? &iy : p.name == "z" ? &iz : nullptr;
      if (slot != nullptr) {
        if (!real) return Status::Unimplemented(path + ": vertex " + p.name + " is not a float");
        *slot = static_cast<int>(k);
      }
    }
    if (ix < 0 || iy < 0 || iz < 0) return Status::InvalidArgument(path + ": vertex lacks x y z");
    points.reserve(e.count);
    if (format == "ascii") {
      std::vector<double> values(e.properties.size());
      for (int64_t i = 0; i < e.count; ++i) {
        for (double& v : values) {
          if (!(in >> v)) return Status::InvalidArgument(path + ": truncated vertex data");
        }
        points.emplace_back(values[ix], values[iy], values[iz]);
      }
    } else {
      std::vector<char> buf(record);
      for (int64_t i = 0; i < e.count; ++i) {
        if (!in.read(buf.data(), record)) {
          return Status::InvalidArgument(path + ": truncated vertex data");
        }
        points.emplace_back(ReadBinaryScalar(buf.data() + offset[ix], e.properties[ix].type),
                            ReadBinaryScalar(buf.data() + offset[iy], e.properties[iy].type),
                            ReadBinaryScalar(buf.data() + offset[iz], e.properties[iz].type));
      }
    }
    return points;
  }
  return Status::InvalidArgument(path + ": no vertex element");
}

}  // namespace mapd::testing
