/*
 * Cortex-M4F test harness (QEMU mps2-an386, semihosting file I/O).
 *
 * Reads input.bin (samples of EDM_COMP_NUM_INPUTS floats, in input order),
 * steps the compensator once per sample and writes output.bin (per sample:
 * each row's output, then the total, as floats). Files are opened on the host
 * through semihosting, relative to QEMU's working folder.
 */
#include <stdio.h>

#include "edm_comp.h"

static edm_comp_state_t state;

int main(void)
{
    edm_comp_real_t u[EDM_COMP_NUM_INPUTS];
    edm_comp_real_t out[EDM_COMP_NUM_ROWS + 1];
    unsigned long n = 0;
    FILE *in = fopen("input.bin", "rb");
    FILE *res = fopen("output.bin", "wb");
    if (in == NULL || res == NULL) {
        printf("harness: cannot open input.bin or output.bin\n");
        return 2;
    }
    edm_comp_init(&state);
    while (fread(u, sizeof u[0], EDM_COMP_NUM_INPUTS, in) == EDM_COMP_NUM_INPUTS) {
        out[EDM_COMP_NUM_ROWS] = edm_comp_step(&state, u, out);
        if (fwrite(out, sizeof out[0], EDM_COMP_NUM_ROWS + 1, res) != EDM_COMP_NUM_ROWS + 1) {
            printf("harness: write failed\n");
            return 3;
        }
        ++n;
    }
    fclose(in);
    fclose(res);
    printf("harness: %lu samples\n", n);
    return 0;
}
