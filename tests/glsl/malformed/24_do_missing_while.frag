// expect: 4:1 expected 'while' after the do-loop body
void main() {
    do { } 
}
