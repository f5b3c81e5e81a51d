// ERROR 4:3 #endif without #if
#if 1
#endif
  #endif
