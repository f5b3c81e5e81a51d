#define A 1 \
  + 2
int x = A; // c
/* a
 b */ int y;
