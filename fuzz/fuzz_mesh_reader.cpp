// Any bytes as a part mesh (.stl: binary told by its size, else ASCII): the reader either
// returns a mesh of finite vertices and valid faces or throws InputError (never crashes,
// hangs or throws anything else).
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <string>

#include "taxopt/core/error.hpp"
#include "taxopt/io/mesh_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = "/tmp/taxopt-fuzz-mesh-" + std::to_string(::getpid()) + ".stl";
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  try {
    const taxopt::TriangleMesh mesh = taxopt::read_mesh_file(path);
    for (const auto& v : mesh.vertices) {
      if (!v.allFinite()) std::abort();
    }
    for (const auto& f : mesh.faces) {
      for (int i : f) {
        if (i < 0 || static_cast<std::size_t>(i) >= mesh.vertices.size()) std::abort();
      }
    }
  } catch (const taxopt::InputError&) {
  }
  return 0;
}
