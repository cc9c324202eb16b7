/* unit.h - the few assertion macros the firmware core's host unit tests use. */
#ifndef PROLEG_TEST_UNIT_H
#define PROLEG_TEST_UNIT_H

#include <stdio.h>
#include <stdlib.h>

static int unit_failures;

#define CHECK(cond)                                                                   \
    do {                                                                              \
        if (!(cond)) {                                                                \
            printf("%s:%d: %s: CHECK(%s) failed\n", __FILE__, __LINE__, __func__, #cond); \
            unit_failures++;                                                          \
            return;                                                                   \
        }                                                                             \
    } while (0)

#define CHECK_EQ(a, b)                                                                           \
    do {                                                                                         \
        long long unit_a = (long long)(a), unit_b = (long long)(b);                              \
        if (unit_a != unit_b) {                                                                  \
            printf("%s:%d: %s: %s == %s failed: %lld != %lld\n", __FILE__, __LINE__, __func__, #a, \
                   #b, unit_a, unit_b);                                                          \
            unit_failures++;                                                                     \
            return;                                                                              \
        }                                                                                        \
    } while (0)

#define RUN(test)                       \
    do {                                \
        int unit_before = unit_failures; \
        test();                         \
        printf("%s %s\n", unit_failures == unit_before ? "ok  " : "FAIL", #test); \
    } while (0)

#define UNIT_EXIT() (unit_failures ? (printf("%d failed\n", unit_failures), EXIT_FAILURE) : EXIT_SUCCESS)

#endif
