// The one exception type of occtrack's file readers: bad input, with a message that names the file, the key
// and the broken rule, e.g. "case.json: inputs.target[2]: expected 4 numbers, got 3".
#pragma once

#include <stdexcept>
#include <string>

namespace occtrack::io {

class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace occtrack::io
