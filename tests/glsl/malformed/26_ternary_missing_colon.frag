// expect: 3:26 expected ':' in the ?: expression
void main() {
    float a = true ? 1.0 ; 2.0;
}
