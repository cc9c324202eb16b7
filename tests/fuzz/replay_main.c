/* replay_main.c - runs a libFuzzer harness over saved inputs without libFuzzer (for the
 * source-coverage build of run_fuzz.py --coverage): argv[1] is a file listing input paths. */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int main(int argc, char **argv)
{
    static uint8_t buf[1 << 16];
    char path[4096];
    FILE *list;
    if (argc < 2 || (list = fopen(argv[1], "r")) == NULL) {
        return 2;
    }
    while (fgets(path, sizeof path, list)) {
        FILE *f;
        size_t n;
        path[strcspn(path, "\n")] = '\0';
        if ((f = fopen(path, "rb")) == NULL) {
            continue;
        }
        n = fread(buf, 1, sizeof buf, f);
        fclose(f);
        LLVMFuzzerTestOneInput(buf, n);
    }
    fclose(list);
    return 0;
}
