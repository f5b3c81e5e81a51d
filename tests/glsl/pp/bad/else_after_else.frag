// ERROR 7:1 #else after #else
#if 0
#else
#if 0
#else
#endif
#else
#endif
