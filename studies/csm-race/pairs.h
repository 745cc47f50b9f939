/* The race's shared part: reading the plain pairs (`cargo run --release --example csm_pairs`),
   the clock, and writing each pair's line and each row's summary. Header-only, included by
   race_csm.c and race_mbicp.c. */
#ifndef CSM_RACE_PAIRS_H
#define CSM_RACE_PAIRS_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

struct pair {
	char row[96];
	int index;
	double tolerance_m, tolerance_rad;
	double guess[3], truth[3];
	double angle_min, angle_increment, range_max;
	int n;
	double *ranges[2]; /* reference, current */
};

/* Reads one pair; 0 at the end of the input, -1 on a malformed line (named on stderr). */
static int read_pair(FILE *in, struct pair *p, int line, int max_beams) {
	int got = fscanf(in, "%95s %d %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %d", p->row,
		&p->index, &p->tolerance_m, &p->tolerance_rad, &p->guess[0], &p->guess[1], &p->guess[2],
		&p->truth[0], &p->truth[1], &p->truth[2], &p->angle_min, &p->angle_increment,
		&p->range_max, &p->n);
	if (got == EOF) return 0;
	if (got != 14 || p->n < 2 || p->n > max_beams) {
		fprintf(stderr, "race: line %d: expected a row's name, 13 numbers and 2..%d beams\n",
			line, max_beams);
		return -1;
	}
	for (int s = 0; s < 2; s++) {
		p->ranges[s] = malloc(sizeof(double) * p->n);
		for (int i = 0; i < p->n; i++) {
			if (fscanf(in, "%lf", &p->ranges[s][i]) != 1) {
				fprintf(stderr, "race: line %d: expected %d ranges a scan\n", line, p->n);
				return -1;
			}
		}
	}
	return 1;
}

/* Whether beam `i` of scan `s` returned something. */
static int returned(const struct pair *p, int s, int i) {
	double r = p->ranges[s][i];
	return isfinite(r) && r > 0 && r < p->range_max;
}

static double now_us(void) {
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return t.tv_sec * 1e6 + t.tv_nsec * 1e-3;
}

static int by_value(const void *a, const void *b) {
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

/* Prints one row's success share and median time to stderr. */
static void summary(const char *row, double *times, int n, int right) {
	if (n == 0) return;
	qsort(times, n, sizeof(double), by_value);
	fprintf(stderr, "%-28s %4d pairs  success %.4f  median %.0f us\n", row, n,
		(double)right / n, times[n / 2]);
}

/* Matches one pair from its guess: fills `answer` (x, y, theta), `iterations`, and returns
   whether the matcher gave an answer. */
typedef int (*match_fn)(const struct pair *p, double answer[3], int *iterations);

/* Reads every pair on stdin, matches each `rounds` times keeping its best time, and writes
   `row,pair,micros,valid,x,y,theta,iterations,error_m,error_rad,success` a pair. */
static int race(match_fn match, int rounds, int max_beams) {
	struct pair p;
	char row[96] = "";
	double *times = malloc(sizeof(double) * 100000);
	int in_row = 0, right = 0, line = 0;
	printf("row,pair,micros,valid,x,y,theta,iterations,error_m,error_rad,success\n");
	for (;;) {
		int got = read_pair(stdin, &p, ++line, max_beams);
		if (got < 0) return 1;
		if (got == 0 || strcmp(p.row, row) != 0) {
			summary(row, times, in_row, right);
			in_row = right = 0;
			if (got == 0) break;
			strcpy(row, p.row);
		}
		if (in_row == 100000) {
			fprintf(stderr, "race: line %d: more than 100000 pairs in row %s\n", line, p.row);
			return 1;
		}
		double best = INFINITY, x[3];
		int valid = 0, iterations = 0;
		for (int k = 0; k < rounds; k++) {
			double start = now_us();
			valid = match(&p, x, &iterations);
			double took = now_us() - start;
			if (took < best) best = took;
		}
		if (!valid) memcpy(x, p.guess, sizeof x);
		/* The answer's distance from the truth, as `twin matchers` measures it. */
		double error_m = hypot(x[0] - p.truth[0], x[1] - p.truth[1]);
		double error_rad = fabs(remainder(x[2] - p.truth[2], 2 * M_PI));
		int success = error_m <= p.tolerance_m && error_rad <= p.tolerance_rad;
		printf("\"%s\",%d,%.1f,%d,%.9f,%.9f,%.9f,%d,%.9f,%.9f,%d\n", p.row, p.index, best, valid,
			x[0], x[1], x[2], valid ? iterations : 0, error_m, error_rad, success);
		times[in_row++] = best;
		right += success;
		free(p.ranges[0]);
		free(p.ranges[1]);
	}
	free(times);
	return 0;
}

static int rounds_from(int argc, char **argv) {
	int rounds = argc > 1 ? atoi(argv[1]) : 5;
	if (rounds < 1) {
		fprintf(stderr, "race: ROUNDS must be a whole number of at least 1\n");
		exit(2);
	}
	return rounds;
}

#endif
