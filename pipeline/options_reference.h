#pragma once
// The options reference (docs/options.md), made from the declared options themselves: every key with its
// default, kind, unit, choices and help, a table per section in the order the stages run. `photo2nerf options`
// prints it, and a test holds docs/options.md to it.

#include <string>

#include "pipeline/options.h"

namespace p2n {

// Markdown: a short introduction, then one table per section.
std::string OptionsReference(const OptionRegistry& registry);

}  // namespace p2n
