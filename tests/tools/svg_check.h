#ifndef CALIB_TESTS_TOOLS_SVG_CHECK_H_
#define CALIB_TESTS_TOOLS_SVG_CHECK_H_

#include <map>
#include <regex>
#include <string>
#include <vector>

// Checks on the SVG files calib writes, without an XML library: tags balanced and properly
// nested, the text a person reads, and the point counts of the named series.
namespace calib::testing {

// "" when every element is closed in order under one <svg> root, else what is wrong.
inline std::string SvgStructureError(const std::string& svg) {
  std::vector<std::string> open;
  int roots = 0;
  for (size_t i = svg.find('<'); i != std::string::npos; i = svg.find('<', i + 1)) {
    const size_t end = svg.find('>', i);
    if (end == std::string::npos) return "unterminated tag at " + std::to_string(i);
    const std::string tag = svg.substr(i + 1, end - i - 1);
    if (tag.empty()) return "empty tag at " + std::to_string(i);
    if (tag[0] == '?' || tag[0] == '!') continue;
    if (tag[0] == '/') {
      const std::string name = tag.substr(1);
      if (open.empty() || open.back() != name) {
        return "</" + name + "> closes " + (open.empty() ? "nothing" : "<" + open.back() + ">");
      }
      open.pop_back();
      continue;
    }
    const std::string name = tag.substr(0, tag.find_first_of(" \n/"));
    if (open.empty()) ++roots;
    if (open.empty() && name != "svg") return "root element <" + name + ">";
    if (tag.back() != '/') open.push_back(name);
    // Attribute quotes must pair up.
    size_t singles = 0, doubles = 0;
    for (char c : tag) singles += c == '\'', doubles += c == '"';
    if (singles % 2 || doubles % 2) return "unpaired quote in <" + name + ">";
  }
  if (!open.empty()) return "<" + open.back() + "> never closed";
  if (roots != 1) return std::to_string(roots) + " root elements";
  return "";
}

// The text of every <text> element (with &lt; &gt; &amp; left as written).
inline std::vector<std::string> SvgTexts(const std::string& svg) {
  std::vector<std::string> texts;
  const std::regex text("<text[^>]*>([^<]*)</text>");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), text); it != std::sregex_iterator();
       ++it) {
    texts.push_back((*it)[1]);
  }
  return texts;
}

// data-points of each series, by its label (summed when a label repeats, e.g. over panels).
inline std::map<std::string, int> SvgSeriesPoints(const std::string& svg) {
  std::map<std::string, int> points;
  const std::regex group("<g data-series='([^']*)' data-points='([0-9]+)'>");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), group); it != std::sregex_iterator();
       ++it) {
    points[(*it)[1]] += std::stoi((*it)[2]);
  }
  return points;
}

inline bool HasText(const std::string& svg, const std::string& wanted) {
  for (const std::string& t : SvgTexts(svg)) {
    if (t.find(wanted) != std::string::npos) return true;
  }
  return false;
}

}  // namespace calib::testing

#endif  // CALIB_TESTS_TOOLS_SVG_CHECK_H_
