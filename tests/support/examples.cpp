// SPDX-License-Identifier: MIT
// Example characters for tests, cached.
#include "examples.h"

#include <gtest/gtest.h>

#include <map>
#include <memory>
#include <mutex>

#include "imps/scene_reader.h"

namespace imps::test {

const Character& exampleCharacter(const std::string& name) {
  static std::mutex mutex;
  static std::map<std::string, std::unique_ptr<Character>> cache;
  std::lock_guard<std::mutex> lock(mutex);
  auto& slot = cache[name];
  if (!slot) {
    auto scene = readSceneFile(std::string(IMPS_SOURCE_DIR) + "/examples/" + name + ".wrl");
    if (!scene) {
      ADD_FAILURE() << scene.error().str();
      std::abort();
    }
    auto character = Character::fromScene(*scene);
    if (!character) {
      ADD_FAILURE() << character.error().str();
      std::abort();
    }
    slot = std::make_unique<Character>(std::move(*character));
  }
  return *slot;
}

}  // namespace imps::test
