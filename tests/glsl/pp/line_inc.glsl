/* first line of line_inc */ float inc;
#line 50
float inc50;
