// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package android.content;

/** Stub of Android's Context: only the type (the first argument of the HardwareMap constructor). */
public abstract class Context {
}
