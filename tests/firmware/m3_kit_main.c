/*
 * The verification kit's run on the Cortex-M3 (tests only): edm_comp_test.c is
 * built with EDM_COMP_TEST_NO_MAIN; this main prints the state size and the
 * verdict (and the deviation without the switching rule) through semihosting,
 * with integers only.
 */
#include <stdint.h>
#include <stdio.h>

#include "edm_comp.h"

int edm_comp_test(int64_t *max_deviation);
int64_t edm_comp_test_raw(void);

int main(void)
{
    int64_t worst = 0;
    const int failed = edm_comp_test(&worst);
    printf("state %u bytes\n", (unsigned)sizeof(edm_comp_state_t));
    printf("without the switching rule: max deviation %lld LSB\n",
           (long long)edm_comp_test_raw());
    printf("%s: max deviation %lld LSB\n", failed ? "FAIL" : "PASS", (long long)worst);
    return failed;
}
