/*
 * editor.h - entry point of the terminal lens editor.
 */
#ifndef SG_EDITOR_H
#define SG_EDITOR_H

/* Runs the editor.  argv[0] is the subcommand ("edit" or the program
 * name), then an optional design file and options:
 *   --batch SCRIPT   run the commands in SCRIPT ("-": standard input)
 *                    without a screen, stopping at the first error
 *   --help           print usage
 * Returns the process exit status. */
int sg_editor_main(int argc, char **argv);

#endif
