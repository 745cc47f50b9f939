/* Censi's CSM, point-to-line ICP as its library ships it (sm_icp with the defaults of
   sm_options.c), timed on the pairs of `twin matchers`' standard rows.

   Reads the pairs `cargo run --release --example csm_pairs -- SEED` writes (one a line) on
   standard input; matches each pair ROUNDS times (default 5) and keeps its best time, as the
   project's race (`cargo bench --bench matcher_race`) does; writes one line a pair to standard
   output:

     row,pair,micros,valid,x,y,theta,iterations,error_m,error_rad,success

   (the row's name quoted, its spaces as `_`)
   and each row's success share and median time to standard error. A pair's time covers
   building both scans' laser_data from their ranges, sm_icp, and freeing them, as the
   project's race times building the reference and matching.

   Build against a CSM checkout: see README.md beside this file. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "csm_all.h"

/* The options sm_options.c gives when nothing is set (CSM's defaults). */
static void csm_defaults(struct sm_params *p) {
	memset(p, 0, sizeof *p);
	p->max_angular_correction_deg = 90.0;
	p->max_linear_correction = 2.0;
	p->max_iterations = 1000;
	p->epsilon_xy = 0.0001;
	p->epsilon_theta = 0.0001;
	p->max_correspondence_dist = 2.0;
	p->sigma = 0.01;
	p->use_corr_tricks = 1;
	p->restart = 1;
	p->restart_threshold_mean_error = 0.01;
	p->restart_dt = 0.01;
	p->restart_dtheta = 1.5 * M_PI / 180.0;
	p->clustering_threshold = 0.05;
	p->orientation_neighbourhood = 3;
	p->use_point_to_line_distance = 1;
	p->do_alpha_test = 0;
	p->do_alpha_test_thresholdDeg = 20.0;
	p->outliers_maxPerc = 0.95;
	p->outliers_adaptive_order = 0.7;
	p->outliers_adaptive_mult = 2.0;
	p->do_visibility_test = 0;
	p->outliers_remove_doubles = 1;
	p->do_compute_covariance = 0;
	p->debug_verify_tricks = 0;
	p->min_reading = 0.0;
	p->max_reading = 1000.0;
	p->use_ml_weights = 0;
	p->use_sigma_weights = 0;
}

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
static int read_pair(FILE *in, struct pair *p, int line) {
	int got = fscanf(in, "%95s %d %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %d", p->row,
		&p->index, &p->tolerance_m, &p->tolerance_rad, &p->guess[0], &p->guess[1], &p->guess[2],
		&p->truth[0], &p->truth[1], &p->truth[2], &p->angle_min, &p->angle_increment,
		&p->range_max, &p->n);
	if (got == EOF) return 0;
	if (got != 14 || p->n < 2 || p->n > 10000) {
		fprintf(stderr, "race: line %d: expected 13 numbers after the row's name, beams 2..10000\n", line);
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

static LDP scan_to_ld(const struct pair *p, const double *ranges) {
	LDP ld = ld_alloc_new(p->n);
	for (int i = 0; i < p->n; i++) {
		double r = ranges[i];
		ld->theta[i] = p->angle_min + i * p->angle_increment;
		int valid = isfinite(r) && r > 0 && r < p->range_max;
		ld->valid[i] = valid;
		ld->readings[i] = valid ? r : GSL_NAN;
	}
	ld->min_theta = ld->theta[0];
	ld->max_theta = ld->theta[p->n - 1];
	return ld;
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

static void summary(const char *row, double *times, int n, int right) {
	if (n == 0) return;
	qsort(times, n, sizeof(double), by_value);
	fprintf(stderr, "%-28s %4d pairs  success %.4f  median %.0f us\n", row, n,
		(double)right / n, times[n / 2]);
}

int main(int argc, char **argv) {
	int rounds = argc > 1 ? atoi(argv[1]) : 5;
	if (rounds < 1) {
		fprintf(stderr, "race: ROUNDS must be a whole number of at least 1\n");
		return 2;
	}
	struct pair p;
	char row[96] = "";
	double *times = malloc(sizeof(double) * 100000);
	int in_row = 0, right = 0, line = 0;
	printf("row,pair,micros,valid,x,y,theta,iterations,error_m,error_rad,success\n");
	for (;;) {
		int got = read_pair(stdin, &p, ++line);
		if (got < 0) return 1;
		if (got == 0 || strcmp(p.row, row) != 0) {
			summary(row, times, in_row, right);
			in_row = right = 0;
			if (got == 0) break;
			strcpy(row, p.row);
		}
		double best = INFINITY;
		struct sm_result res;
		for (int k = 0; k < rounds; k++) {
			double start = now_us();
			struct sm_params params;
			csm_defaults(&params);
			params.laser_ref = scan_to_ld(&p, p.ranges[0]);
			params.laser_sens = scan_to_ld(&p, p.ranges[1]);
			memcpy(params.first_guess, p.guess, sizeof p.guess);
			sm_icp(&params, &res);
			ld_free(params.laser_ref);
			ld_free(params.laser_sens);
			double took = now_us() - start;
			if (took < best) best = took;
		}
		double x[3] = {p.guess[0], p.guess[1], p.guess[2]};
		if (res.valid) memcpy(x, res.x, sizeof x);
		/* The answer's error in the truth's frame, as `twin matchers` measures it. */
		double dx = x[0] - p.truth[0], dy = x[1] - p.truth[1];
		double error_m = hypot(dx, dy);
		double error_rad = fabs(remainder(x[2] - p.truth[2], 2 * M_PI));
		int success = error_m <= p.tolerance_m && error_rad <= p.tolerance_rad;
		printf("\"%s\",%d,%.1f,%d,%.9f,%.9f,%.9f,%d,%.9f,%.9f,%d\n", p.row, p.index, best, res.valid,
			x[0], x[1], x[2], res.valid ? res.iterations : 0, error_m, error_rad, success);
		times[in_row++] = best;
		right += success;
		free(p.ranges[0]);
		free(p.ranges[1]);
	}
	free(times);
	return 0;
}
