/* Minguez, Montesano and Lamiraux's MbICP, their C library as CSM and Player carry it
   (MbICPmatcher), timed on the pairs of `twin matchers`' standard rows, with the parameters
   of Player's mbicp driver (its configuration's defaults) but the laser's range: each scan's
   no-return limit, so that MbICP's "longer than the range" rule drops exactly the no-returns.

   race_mbicp [ROUNDS] < pairs.txt > mbicp.csv

   Input, output and timing as race_csm.c (pairs.h). A pair's time covers filling the two
   polar scans, MbICPmatcher and nothing else: the library keeps its state in static arrays.
   MbICP's scans hold at most MAXLASERPOINTS (361) beams; the unused tail is filled with
   readings beyond the range, which its preprocessing skips. The library does not report how
   many iterations it made: the `iterations` column holds its return code instead (1: it
   converged, 2: it stopped at MaxIter). */
#include "MbICP.h"
#include "pairs.h"

/* Player's mbicp driver (server/drivers/position/mbicp/mbicp_driver.cc), its defaults. */
#define BW (1.57f / 3.0f)  /* angular_window, rad */
#define BR 0.3f            /* radial_window, m */
#define L_METRIC 3.0f      /* L, m */
#define LASER_STEP 1
#define MAX_DIST_INTER 0.5f
#define FILTER 0.85f
#define PROJECTION_FILTER 1
#define ASOC_ERROR 0.1f
#define MAX_ITER 50
#define ERROR_RATIO 0.0001f
#define ERR_OUT 0.0001f
#define ITER_SMOOTH_CONV 2

static int match_mbicp(const struct pair *p, double answer[3], int *iterations) {
	static Tpfp scans[2][MAXLASERPOINTS];
	float beyond = (float)p->range_max * 2.0f + 1.0f;
	for (int s = 0; s < 2; s++) {
		for (int i = 0; i < MAXLASERPOINTS; i++) {
			scans[s][i].t = (float)(p->angle_min + i * p->angle_increment);
			scans[s][i].r = i < p->n && returned(p, s, i) ? (float)p->ranges[s][i] : beyond;
		}
	}
	Init_MbICP_ScanMatching((float)p->range_max, BW, BR, L_METRIC, LASER_STEP, MAX_DIST_INTER,
		FILTER, PROJECTION_FILTER, ASOC_ERROR, MAX_ITER, ERROR_RATIO, ERR_OUT, ERR_OUT, ERR_OUT,
		ITER_SMOOTH_CONV);
	Tsc guess = {(float)p->guess[0], (float)p->guess[1], (float)p->guess[2]};
	Tsc solution = guess;
	int outcome = MbICPmatcher(scans[0], scans[1], &guess, &solution);
	/* 1: converged; 2: stopped at MaxIter with an estimate; -1, -2: no estimate. */
	if (outcome != 1 && outcome != 2) return 0;
	answer[0] = solution.x;
	answer[1] = solution.y;
	answer[2] = solution.tita;
	*iterations = outcome; /* the library does not report its iteration count */
	return 1;
}

int main(int argc, char **argv) {
	return race(match_mbicp, rounds_from(argc, argv), MAXLASERPOINTS);
}
