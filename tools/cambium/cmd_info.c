/* cambium info FILE: what a file holds. For now: the kind of file by extension and its size;
 * each subsystem adds what it can read. */
#include "cli.h"
#include "commands.h"

#include <string.h>
#include <sys/stat.h>

int cmd_info(int argc, char **argv)
{
    if (argc != 2 || !strcmp(argv[1], "--help")) {
        if (argc == 2) {
            printf("usage: cambium info FILE\n\nSays what a model or output file holds.\n");
            return CLI_OK;
        }
        return cli_usage_error("info", "expected one FILE");
    }
    struct stat st;
    if (stat(argv[1], &st) != 0) {
        fprintf(stderr, "cambium: %s: cannot open\n", argv[1]);
        return CLI_FAIL;
    }
    printf("%s: %s file, %lld bytes\n", argv[1], cli_extension(argv[1]), (long long)st.st_size);
    return CLI_OK;
}
