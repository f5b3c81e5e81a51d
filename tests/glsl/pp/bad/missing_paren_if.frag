// ERROR 2:5 missing ')' in #if expression
#if (1 + 2
#endif
