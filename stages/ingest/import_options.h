#pragma once
// The import stage's options (import.*), apart from the stage so that others include them alone.

#include "pipeline/options.h"

namespace p2n {

// import.background: keep records none.
enum class ImportBackground { kWhite, kBlack, kKeep };
template <>
struct EnumNames<ImportBackground> {
  static constexpr std::pair<ImportBackground, const char*> kValues[] = {
      {ImportBackground::kWhite, "white"}, {ImportBackground::kBlack, "black"}, {ImportBackground::kKeep, "keep"}};
};

struct ImportOptions {
  static constexpr const char* kSection = "import";  // its options are import.NAME

  ImportBackground background = ImportBackground::kWhite;  // transparent images are shown and scored on it

  template <class V>
  void Visit(V& v) {
    v("background", background,
      "the colour transparent (RGBA) images are shown and scored on (their alpha is kept: training puts random "
      "colours behind them); keep: no colour recorded (shown on white)");
  }
  void Check() const {}
};

}  // namespace p2n
