// expect: 3:15 invalid number
void main() {
    float a = 1.5q;
}
