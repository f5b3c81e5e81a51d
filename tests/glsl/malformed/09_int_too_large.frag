// expect: 3:13 does not fit in 32 bits
void main() {
    int a = 99999999999;
}
