/* The chapter's run as a bare C program on libmujoco alone: the baseline of
   bench/bench_process.py, which measures the whole process `sim_loop --seed 0`
   against it.

     build/bare_chapter OUT STEPS SHOVE_START SHOVE_STEPS SHOVE_Y SEED [binary|csv]

   It loads the scene from the XML text sim_loop loads (cpp/chapter_scene.cc's, put in
   a header by cmake/SceneXmlHeader.cmake) through a one-file virtual file
   system as sim_loop does, sets ctrl[0] = 1, writes SHOVE_Y newtons in y on
   the box from step SHOVE_START for SHOVE_STEPS steps (the benchmark reads the
   shove sim_loop drew from its trajectory.csv), and steps STEPS times with
   mj_step, keeping the same rows sim_loop's trajectory.csv holds: before each
   step the step, time, ctrl, the shove's force, the box's qpos and qvel, the
   pusher's, ncon, and the final state (NaN where the final row has no inputs).
   Then it writes OUT/metrics.json, the same bytes as sim_loop's, and the rows:
   OUT/trajectory.f64 (binary: the rows as raw doubles, the cheapest exact way
   C has) or OUT/trajectory.csv (csv: printf's "%.17g", exact too).
   It prints one line. Plain C: the only library it calls is libmujoco. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mujoco/mujoco.h>

#include "pusher_scene_xml.h" /* kPusherSceneXml */

enum { kColumns = 22 };
static const char* const kHeader =
    "step,time,ctrl,shove_x,shove_y,shove_z,box_x,box_y,box_z,box_qw,box_qx,box_qy,box_qz,"
    "box_vx,box_vy,box_vz,box_wx,box_wy,box_wz,pusher_x,pusher_vx,ncon\n";

static void die(const char* what, const char* detail) {
  fprintf(stderr, "bare_chapter: %s%s%s\n", what, detail ? ": " : "", detail ? detail : "");
  exit(1);
}

/* The scene from memory, as sim_loop loads it. */
static mjModel* load_scene(void) {
  char error[1000] = "";
  const int size = (int)strlen(kPusherSceneXml);
  mjModel* m = NULL;
#if mjVERSION_HEADER >= 300
  mjVFS vfs;
  mj_defaultVFS(&vfs);
  if (mj_addBufferVFS(&vfs, "model.xml", kPusherSceneXml, size) != 0) die("cannot hold the XML in a VFS", NULL);
  m = mj_loadXML("model.xml", &vfs, error, sizeof error);
  mj_deleteVFS(&vfs);
#else
  mjVFS* vfs = malloc(sizeof *vfs); /* 2 MB in MuJoCo 2.2 */
  if (!vfs) die("out of memory", NULL);
  mj_defaultVFS(vfs);
  if (mj_makeEmptyFileVFS(vfs, "model.xml", size) != 0) die("cannot hold the XML in a VFS", NULL);
  memcpy(vfs->filedata[vfs->nfile - 1], kPusherSceneXml, (size_t)size);
  m = mj_loadXML("model.xml", vfs, error, sizeof error);
  mj_deleteVFS(vfs);
  free(vfs);
#endif
  if (!m) die("cannot load the scene", error);
  return m;
}

/* One row: the state entering a step and the inputs written for it. */
static void record(double* row, long long step, const mjData* d, int box_q, int box_v, int box_body, int pusher_q,
                   int pusher_v, int inputs) {
  row[0] = (double)step;
  row[1] = d->time;
  for (int i = 0; i < 4; ++i) row[2 + i] = NAN;
  if (inputs) {
    row[2] = d->ctrl[0];
    for (int i = 0; i < 3; ++i) row[3 + i] = d->xfrc_applied[6 * box_body + i];
  }
  for (int i = 0; i < 7; ++i) row[6 + i] = d->qpos[box_q + i];
  for (int i = 0; i < 6; ++i) row[13 + i] = d->qvel[box_v + i];
  row[19] = d->qpos[pusher_q];
  row[20] = d->qvel[pusher_v];
  row[21] = d->ncon;
}

/* Python's round(x, 6), as simloop's metrics round. */
static double round6(double x) {
  char text[400];
  snprintf(text, sizeof text, "%.6f", x);
  return strtod(text, NULL);
}

/* Python's repr(float) of a finite x: the fewest digits that read back as x,
   laid out as Python lays them out (metrics.json is json.dumps's text). */
static void python_repr(double x, char* out) {
  char sci[40];
  for (int digits = 1; digits <= 17; ++digits) {
    snprintf(sci, sizeof sci, "%.*e", digits - 1, x);
    if (strtod(sci, NULL) == x) break;
  }
  char mantissa[24];
  int n = 0;
  const char* p = sci;
  if (*p == '-') *out++ = *p++;
  for (; *p != 'e'; ++p) {
    if (*p != '.') mantissa[n++] = *p;
  }
  const int exponent = atoi(p + 1);
  const int point = exponent + 1;
  if (point > 16 || point < -3) {
    *out++ = mantissa[0];
    if (n > 1) *out++ = '.';
    for (int i = 1; i < n; ++i) *out++ = mantissa[i];
    sprintf(out, "e%c%02d", exponent < 0 ? '-' : '+', abs(exponent));
  } else if (point <= 0) {
    out += sprintf(out, "0.");
    for (int i = 0; i < -point; ++i) *out++ = '0';
    sprintf(out, "%.*s", n, mantissa);
  } else if (point >= n) {
    out += sprintf(out, "%.*s", n, mantissa);
    for (int i = n; i < point; ++i) *out++ = '0';
    sprintf(out, ".0");
  } else {
    sprintf(out, "%.*s.%.*s", point, mantissa, n - point, mantissa + point);
  }
}

/* A row as raw doubles, or as CSV text (the final row's inputs empty). */
static void write_row(FILE* f, const double* row, int csv) {
  if (!csv) {
    fwrite(row, sizeof(double), kColumns, f);
    return;
  }
  fprintf(f, "%lld", (long long)row[0]);
  for (int c = 1; c < kColumns - 1; ++c) {
    if (isnan(row[c])) {
      fputc(',', f);
    } else {
      fprintf(f, ",%.17g", row[c]);
    }
  }
  fprintf(f, ",%d\n", (int)row[kColumns - 1]);
}

static FILE* open_output(const char* dir, const char* name, char* path) {
  snprintf(path, 4096, "%s/%s", dir, name);
  FILE* f = fopen(path, "w");
  if (!f) die("cannot write", path);
  return f;
}

static void close_output(FILE* f, const char* path) {
  if (ferror(f) || fclose(f) != 0) die("cannot write", path);
}

int main(int argc, char** argv) {
  if (argc < 7 || argc > 8 || (argc == 8 && strcmp(argv[7], "binary") != 0 && strcmp(argv[7], "csv") != 0)) {
    fprintf(stderr, "usage: bare_chapter OUT STEPS SHOVE_START SHOVE_STEPS SHOVE_Y SEED [binary|csv]\n");
    return 2;
  }
  const char* out = argv[1];
  const long long steps = atoll(argv[2]), shove_start = atoll(argv[3]), shove_steps = atoll(argv[4]);
  const double shove_y = strtod(argv[5], NULL);
  const char* seed = argv[6];
  const int csv = argc == 8 && strcmp(argv[7], "csv") == 0;
  if (steps < 1) die("STEPS must be at least 1", NULL);

  mjModel* m = load_scene();
  mjData* d = mj_makeData(m);
  if (!d) die("cannot make the model's mjData", NULL);
  const int box = mj_name2id(m, mjOBJ_BODY, "box");
  const int box_q = m->jnt_qposadr[m->body_jntadr[box]], box_v = m->jnt_dofadr[m->body_jntadr[box]];
  const int pusher_q = m->jnt_qposadr[m->actuator_trnid[0]], pusher_v = m->jnt_dofadr[m->actuator_trnid[0]];
  char path[4096];
  FILE* rows_file = csv ? open_output(out, "trajectory.csv", path) : open_output(out, "trajectory.f64", path);
  if (csv) fputs(kHeader, rows_file);

  /* The loop: write intent, write interference, keep the row, step. */
  mj_forward(m, d);
  double row[kColumns], box_y_at_shove = 0.0;
  for (long long step = 0; step < steps; ++step) {
    d->ctrl[0] = 1.0;
    if (step == shove_start) d->xfrc_applied[6 * box + 1] = shove_y;
    if (step == shove_start + shove_steps) d->xfrc_applied[6 * box + 1] = 0.0;
    if (step == shove_start) box_y_at_shove = d->xpos[3 * box + 1];
    record(row, step, d, box_q, box_v, box, pusher_q, pusher_v, 1);
    write_row(rows_file, row, csv);
    mj_step(m, d);
  }
  record(row, steps, d, box_q, box_v, box, pusher_q, pusher_v, 0);
  write_row(rows_file, row, csv);
  close_output(rows_file, path);

  /* metrics.json, as sim_loop writes it. */
  const double* q = d->qpos + box_q;
  const double* v = d->qvel + box_v;
  const double speed = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  const double drift = fabs(q[1] - box_y_at_shove);
  char x[3][40], speed_text[40], drift_text[40], pusher_text[40];
  for (int i = 0; i < 3; ++i) python_repr(round6(q[i]), x[i]);
  python_repr(round6(speed), speed_text);
  python_repr(round6(drift), drift_text);
  python_repr(round6(d->qpos[pusher_q]), pusher_text);
  FILE* f = open_output(out, "metrics.json", path);
  fprintf(f,
          "{\n  \"box_final_pos\": [\n    %s,\n    %s,\n    %s\n  ],\n  \"box_final_speed\": %s,\n"
          "  \"lateral_drift\": %s,\n  \"perturb\": true,\n  \"pusher_final_x\": %s,\n  \"seed\": %s,\n"
          "  \"shove_moved_box\": %s,\n  \"steps\": %lld\n}\n",
          x[0], x[1], x[2], speed_text, drift_text, pusher_text, seed, drift > 0.01 ? "true" : "false", steps);
  close_output(f, path);

  printf("bare_chapter: %lld steps, box final x %.3f; wrote %s\n", steps, q[0], out);

  mj_deleteData(d);
  mj_deleteModel(m);
  return 0;
}
