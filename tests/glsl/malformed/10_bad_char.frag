// expect: 3:15 unexpected character '@'
void main() {
    float a = @b;
}
