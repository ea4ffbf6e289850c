// docs/development.md's "Where things live" names every folder of src/ and no other: a reader
// of the map finds each room, and a new room cannot go unmapped.
#include <catch2/catch.hpp>
#include <filesystem>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include "support.hpp"

using namespace taxopt::test;

TEST_CASE("layout: docs/development.md maps every folder of src/ and no other", "[docs]") {
  const std::string root = TAXOPT_SOURCE_DIR;
  std::set<std::string> folders;
  for (const auto& e : std::filesystem::directory_iterator(root + "/src")) {
    if (e.is_directory()) folders.insert("src/" + e.path().filename().string() + "/");
  }
  REQUIRE(folders.size() > 5);
  const std::string doc = read_file(root + "/docs/development.md");
  const std::size_t at = doc.find("## Where things live");
  REQUIRE(at != std::string::npos);
  const std::size_t end = doc.find("\n## ", at + 1);
  std::istringstream section(doc.substr(at, end - at));
  std::set<std::string> mapped;
  const std::regex row(R"(^\| `(src/[a-z_]+/)` \|)");
  for (std::string line; std::getline(section, line);) {
    std::smatch m;
    if (std::regex_search(line, m, row)) mapped.insert(m[1]);
  }
  for (const std::string& f : folders) {
    INFO(f << " is not in the map");
    CHECK(mapped.count(f) == 1);
  }
  for (const std::string& f : mapped) {
    INFO(f << " is mapped but is no folder");
    CHECK(folders.count(f) == 1);
  }
}
