// ERROR 3:1 #elif without #if
float a;
#elif 1
