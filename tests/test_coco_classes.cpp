#include <catch2/catch.hpp>

#include <set>
#include <string>

#include "cge/segmentation/coco_classes.hpp"

TEST_CASE("COCO class table: names and ids are each other's inverse", "[coco]") {
  std::set<std::string> seen;
  for (int id = 0; id < cge::kCocoClassCount; ++id) {
    const auto name = cge::coco_class_name(id);
    CHECK_FALSE(name.empty());
    CHECK(seen.insert(std::string(name)).second);  // no name twice
    CHECK(cge::coco_class_id(name) == id);
  }
}

TEST_CASE("COCO class table: ids as YOLOv8 numbers them", "[coco]") {
  CHECK(cge::coco_class_name(cge::kCocoPerson) == "person");
  CHECK(cge::coco_class_id("chair") == 56);
  CHECK(cge::coco_class_id("tv") == 62);
  CHECK(cge::coco_class_id("toothbrush") == 79);
  CHECK_FALSE(cge::coco_class_id("Person").has_value());
  CHECK_FALSE(cge::coco_class_id("unicorn").has_value());
}

TEST_CASE("COCO class table: an id out of range names itself", "[coco]") {
  CHECK_THROWS_WITH(cge::coco_class_name(80), Catch::Contains("class id 80"));
  CHECK_THROWS_WITH(cge::coco_class_name(-1), Catch::Contains("class id -1"));
}
