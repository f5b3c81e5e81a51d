// expect: 3:14 expected ')' after the if condition
void main() {
    if (true ; ) {}
}
