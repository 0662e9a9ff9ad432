// libFuzzer target: fuzz_inputs.h's Image().
#include "fuzz/fuzz_inputs.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  catgraph::fuzz::Image({reinterpret_cast<const char*>(data), size});
  return 0;
}
