// expect: 2:11 expected lowp, mediump or highp after 'precision', found 'float'
precision float;
void main() {}
