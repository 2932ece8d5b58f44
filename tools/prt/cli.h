/* Shared pieces of the prt command line: exit codes, option helpers, progress, lighting. */
#ifndef PRT_CLI_H
#define PRT_CLI_H

#include <prt/prt.h>
#include <stdbool.h>

/* Exit codes, documented in docs/CLI.md and every --help. */
enum {
    EXIT_OK = 0,
    EXIT_FAILURE_INPUT = 1,   /* a file is missing, unreadable, malformed or empty */
    EXIT_USAGE = 2,           /* bad command line */
    EXIT_BACKEND = 3,         /* Embree, OpenGL/EGL or the system failed */
    EXIT_NO_MEMORY = 4,
    EXIT_INTERRUPTED = 130    /* cancelled by SIGINT; nothing was written */
};

#define EXIT_CODES_HELP \
    "Exit codes: 0 success, 1 bad or missing input, 2 usage error, 3 backend failure,\n" \
    "            4 out of memory, 130 interrupted (no output written).\n"

typedef struct cli {
    bool quiet;
    int threads;
    prt_context *ctx;
    const char *cmd;
} cli;

/* Prints "prt CMD: message" on stderr. */
void cli_error(const cli *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Reports the library's last error and maps the status to an exit code. */
int cli_fail(const cli *c, prt_status st);
int cli_usage(const cli *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
int cli_make_context(cli *c);

bool cli_parse_int(const char *s, int lo, int hi, int *out);
bool cli_parse_float(const char *s, float *out);
/* "a,b,c" (or one number, repeated, when allow_scalar). */
bool cli_parse_vec3(const char *s, bool allow_scalar, float out[3]);

/* A progress callback drawing a bar with ETA on stderr when it is a terminal. */
int cli_progress(void *user, const char *stage, uint64_t done, uint64_t total);
/* Installs a SIGINT handler that makes cli_progress cancel the running operation. */
void cli_catch_interrupt(void);
bool cli_interrupted(void);

/* Distant lighting options shared by relight, render and env. */
typedef struct cli_light {
    const char *env_path;     /* NULL: the procedural sky */
    prt_env_layout layout;
    float rotate[3];          /* yaw, pitch, roll in degrees */
    float intensity;          /* multiplier; commands start it at 1 */
    float sun_dir[3];         /* sky only; zero = default */
    bool set_source, set_rotate, set_intensity;   /* what the command line gave explicitly */
    char path_buf[1024];
} cli_light;

#define CLI_LIGHT_OPTIONS_HELP \
    "Lighting:\n" \
    "  --env FILE            environment probe (.hdr .pfm .exr .png); default: procedural sky\n" \
    "  --layout L            latlong | angular | cross | auto (default auto, from aspect ratio)\n" \
    "  --rotate Y[,P[,R]]    rotate the lighting: yaw about +y, pitch, roll in degrees\n" \
    "  --intensity S         scale the lighting (default 1)\n" \
    "  --sun X,Y,Z           sun direction of the procedural sky\n"

/* Returns 1 if the option was a lighting option (consumed), 0 if not, -1 on a bad value. */
int cli_light_option(const cli *c, cli_light *l, int opt, const char *arg);
enum { OPT_ENV = 1000, OPT_LAYOUT, OPT_ROTATE, OPT_INTENSITY, OPT_SUN };
#define CLI_LIGHT_LONG_OPTIONS \
    {"env", required_argument, 0, OPT_ENV}, {"layout", required_argument, 0, OPT_LAYOUT}, \
    {"rotate", required_argument, 0, OPT_ROTATE}, {"intensity", required_argument, 0, OPT_INTENSITY}, \
    {"sun", required_argument, 0, OPT_SUN}
/* Fills what the command line left unset from the lighting a .prt's scene named. */
void cli_light_defaults_from(cli_light *l, const prt_transfer *t);
/* Loads the environment (or builds the sky) and projects it to SH of the given order. */
prt_status cli_light_project(const cli *c, const cli_light *l, int order, prt_sh_light *out, prt_envmap **env_out);

/* The richest kind a file holds, for commands where --kind is optional. */
prt_transfer_kind cli_default_kind(const prt_transfer *t);

int cmd_bake(int argc, char **argv);
int cmd_relight(int argc, char **argv);
int cmd_render(int argc, char **argv);
int cmd_env(int argc, char **argv);
int cmd_info(int argc, char **argv);
int cmd_demo_scene(int argc, char **argv);

#endif
