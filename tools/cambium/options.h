/* The option parser of the tool: each command describes its options in one table, one row per
 * option {name, kind, target, help}, and cli_options_parse walks the command line through it;
 * the same rows print the option lines of the command's --help, so the help cannot forget an
 * option the parser takes. The limit and output options shared by several commands are tables
 * of their own (cli_limit_options, cli_output_options), joined to a command's table by a
 * CLI_GROUP row.
 *
 * Error messages are templates in which {opt} becomes the option as typed, {value} its value and
 * {max} the capacity of a list: "{opt} must be 0..1000". */
#ifndef CBM_CLI_OPTIONS_H
#define CBM_CLI_OPTIONS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

/// What a row does with its option.
typedef enum cli_kind {
    CLI_END = 0,    ///< ends a table
    CLI_HELP,       ///< prints the table's help and stops (the command then exits 0)
    CLI_SET,        ///< bool *target = true
    CLI_CLEAR,      ///< bool *target = false
    CLI_LONG,       ///< long *target = the value, an integer in [min, max]
    CLI_INT,        ///< int *target = the value, an integer in [min, max]
    CLI_TEXT,       ///< const char **target = the value
    CLI_LIST,       ///< the value appended to the cli_list *target
    CLI_CUSTOM,     ///< parse(value, target, ...) checks and stores the value
    CLI_POSITIONAL, ///< a word that is not an option: parse(word, target, ...); one per table
    CLI_GROUP,      ///< the options of another table (const cli_opts *target)
    CLI_DOC,        ///< a help line only (name is the label), never matched
} cli_kind;

/// Parses value into target; false with the reason in why (a template; empty: the row's bad).
typedef bool (*cli_parse_fn)(const char *value, void *target, char *why, size_t why_size);

/// A row of a table.
typedef struct cli_opt {
    const char *name; ///< "--seed"; aliases with '|': "-y|-n|--years"
    cli_kind kind;
    void *target;
    const char *arg;    ///< the value's placeholder in the help ("N"), NULL for a flag
    const char *help;   ///< the help text ('\n' continues it), NULL: not in the help
    const char *bad;    ///< a bad value (template), a missing one too when the table has no missing
    long min, max;      ///< CLI_LONG, CLI_INT
    cli_parse_fn parse; ///< CLI_CUSTOM, CLI_POSITIONAL
    bool attached;      ///< "-DNAME=VALUE" as well as "-D NAME=VALUE"
    bool required;      ///< must be given (the table's `required` message otherwise)
    bool seen;          ///< set by the parser
} cli_opt;

/// A command's table and its messages.
typedef struct cli_opts {
    const char *cmd;                        ///< "run": messages read "cambium run: ..."
    cli_opt *opts;                          ///< the rows, ended by a CLI_END row
    void (*help)(const struct cli_opts *t); ///< what CLI_HELP prints
    const char *title;        ///< heading of a group's section in the help ("limits ...:")
    int width;                ///< help column of the texts
    const char *unknown;      ///< an unknown option: "unknown option '{opt}'"
    const char *unknown_last; ///< an unknown option as the last word (NULL: unknown)
    const char *missing;      ///< a missing value (NULL: the row's bad, else unknown)
    const char *required;     ///< a required option absent: "{opt} is required"
} cli_opts;

/// A list an option appends to (-o FILE, -D NAME=VALUE).
typedef struct cli_list {
    const char **items;
    int count, max;
    const char *full; ///< the message when max items are there: "at most {max} outputs"
} cli_list;

/// What cli_options_parse returns besides CLI_OK and CLI_USAGE.
enum { CLI_HELP_SHOWN = -1 };

/// Parses argv[1..argc) through t: CLI_OK, CLI_USAGE after a usage error (printed), or
/// CLI_HELP_SHOWN after --help.
int cli_options_parse(cli_opts *t, int argc, char **argv);
/// The index of the first word of argv[from..argc) that is neither an option of t nor an
/// option's value, as cli_options_parse would read the line but storing nothing (argc if there
/// is none); an option t does not know counts as a flag. For a command that hands its line to
/// another by the model it names (run to grow, grow to Oberlaender's grow) before parsing it.
int cli_options_next_word(cli_opts *t, int argc, char **argv, int from);
/// The option lines of t, then those of its groups, each group under its title.
void cli_options_help(FILE *f, const cli_opts *t);
/// The two halves of cli_options_help, for a help that says more between them.
void cli_options_rows(FILE *f, const cli_opts *t);
void cli_options_groups(FILE *f, const cli_opts *t);
/// Appends to a list: false when it is full.
bool cli_list_add(cli_list *l, const char *item);
/// A CLI_POSITIONAL parser for commands that take one file (const char **target): a second word
/// is "expected one SPEC, found '{value}' too".
bool cli_parse_one_spec(const char *word, void *target, char *why, size_t n);

/// The limit options (--max-memory MB, ...; main.c) and the output options (--size, --view, ...
/// into *o; cli_output.c), for a CLI_GROUP row.
cli_opts *cli_limit_options(void);
struct cbm_write_options;
cli_opts *cli_output_options(struct cbm_write_options *o);

#endif
