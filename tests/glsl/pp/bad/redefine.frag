// ERROR 3:9 macro 'N' redefined differently
#define N 4
#define N 5
