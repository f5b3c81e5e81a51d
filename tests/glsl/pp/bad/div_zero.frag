// ERROR 3:11 division by zero
#define ZERO (1 - 1)
#if 1 + 4 / ZERO
#endif
