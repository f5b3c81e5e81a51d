// ERROR 3:11 unterminated call of macro 'F'
#define F(x) x
float m = F(1.0,
#define G 2
);
