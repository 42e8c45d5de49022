/* test_sins.c — placeholder replaced by the strapdown C test. */
#include "gf_sins.h"
#include "gf_test.h"

int main(void)
{
    gf_sins_config cfg;
    gf_sins_config_default(&cfg);
    CHECK(cfg.coning == 1, "default coning on");
    TEST_MAIN_END();
}
