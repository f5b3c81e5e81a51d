// ERROR 2:11 unexpected '3' in #if expression
#if 1 + 3 3
#endif
