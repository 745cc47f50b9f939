/* Censi's CSM, point-to-line ICP as its library ships it (sm_icp with the defaults of
   sm_options.c), timed on the pairs of `twin matchers`' standard rows.

   race_csm [ROUNDS] < pairs.txt > csm.csv

   Reads the pairs `cargo run --release --example csm_pairs -- SEED` writes (one a line) on
   standard input; matches each pair ROUNDS times (default 5) and keeps its best time, as the
   project's race (`cargo bench --bench matcher_race`) does; writes one line a pair to standard
   output (pairs.h: row,pair,micros,valid,x,y,theta,iterations,error_m,error_rad,success, the
   row's name quoted) and each row's success share and median time to standard error. A pair's
   time covers building both scans' laser_data from their ranges, sm_icp, and freeing them, as
   the project's race times building the reference and matching.

   Build against a CSM checkout: see README.md beside this file. */
#include "csm_all.h"
#include "pairs.h"

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

static LDP scan_to_ld(const struct pair *p, int s) {
	LDP ld = ld_alloc_new(p->n);
	for (int i = 0; i < p->n; i++) {
		ld->theta[i] = p->angle_min + i * p->angle_increment;
		ld->valid[i] = returned(p, s, i);
		ld->readings[i] = ld->valid[i] ? p->ranges[s][i] : GSL_NAN;
	}
	ld->min_theta = ld->theta[0];
	ld->max_theta = ld->theta[p->n - 1];
	return ld;
}

static int match_csm(const struct pair *p, double answer[3], int *iterations) {
	struct sm_params params;
	struct sm_result res;
	csm_defaults(&params);
	params.laser_ref = scan_to_ld(p, 0);
	params.laser_sens = scan_to_ld(p, 1);
	memcpy(params.first_guess, p->guess, sizeof p->guess);
	sm_icp(&params, &res);
	ld_free(params.laser_ref);
	ld_free(params.laser_sens);
	if (!res.valid) return 0;
	memcpy(answer, res.x, 3 * sizeof(double));
	*iterations = res.iterations;
	return 1;
}

int main(int argc, char **argv) {
	return race(match_csm, rounds_from(argc, argv), 10000);
}
