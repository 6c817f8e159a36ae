// OptionTable declared only: its header compiles CLI11's (about 10 s per
// translation unit), which only the files declaring options need.
#pragma once

namespace docunfold {
class OptionTable;
}  // namespace docunfold
