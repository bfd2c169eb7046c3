/* probe.c - the smallest libFuzzer target; run.sh links it to learn whether
 * clang's -fsanitize=fuzzer works here. */
#include <stddef.h>
#include <stdint.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    (void)data;
    (void)size;
    return 0;
}
