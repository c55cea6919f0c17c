// Keyed input errors (hsr/common.hpp): the library's neutral wording of a setting, which what()
// uses; the command line and the Python module word the same errors in their own terms.
#include <hsr/common.hpp>

namespace hsr {
namespace {

// The setting as the library names it in what(). The memory limit has no name there: the
// detail already says "the memory limit".
const char* neutralName(Setting setting) {
  switch (setting) {
    case Setting::None: return "";
    case Setting::Algorithm: return "algorithm";
    case Setting::Param: return "parameter";
    case Setting::Size: return "size";
    case Setting::DepthFormat: return "depth format";
    case Setting::Verify: return "verify";
    case Setting::SwitchOff: return "tiled switch";
    case Setting::Svg: return "vector output";
    case Setting::OverdrawImage: return "overdraw picture";
    case Setting::ShadowMapSize: return "shadow map size";
    case Setting::ShadowBias: return "shadow bias";
    case Setting::MaxMemory: return "";
  }
  return "";
}

// The one layout of a keyed message, for what() and every front end (InputError::worded).
std::string layout(Setting setting, const std::string& name, const std::string& subject, const std::string& detail) {
  if (setting == Setting::MaxMemory) return subject + " " + detail + (name.empty() ? "" : " (" + name + ")");
  std::string head = name;
  if (!subject.empty()) head += (head.empty() ? "" : " ") + subject;
  return head.empty() ? detail : head + ": " + detail;
}

const std::string kEmpty;

}  // namespace

InputError::InputError(Setting setting, std::string subject, std::string detail)
    : std::runtime_error(layout(setting, neutralName(setting), subject, detail)),
      key_(std::make_shared<const Key>(Key{setting, std::move(subject), std::move(detail)})) {}

const std::string& InputError::subject() const { return key_ ? key_->subject : kEmpty; }
const std::string& InputError::detail() const { return key_ ? key_->detail : kEmpty; }

std::string InputError::worded(const std::string& name, const std::string& subject) const {
  if (!key_) return what();
  return layout(key_->setting, name, subject, key_->detail);
}

}  // namespace hsr
