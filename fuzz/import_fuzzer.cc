// libFuzzer target: fuzz_inputs.h's ImportRecording().
#include "fuzz/fuzz_inputs.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  catgraph::fuzz::ImportRecording({reinterpret_cast<const char*>(data), size});
  return 0;
}
