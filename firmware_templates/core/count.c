/* count.c - see count.h. */
#include "count.h"

#if defined(__GNUC__)
__attribute__((noinline))
#endif
void count_up(uint32_t *counter)
{
    ++*counter;
}
