// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package org.firstinspires.ftc.robotcore.internal.system;

import java.io.File;

/**
 * Stub: the storage folders only. On a Control Hub or phone ROOT_FOLDER is the external storage
 * directory (/sdcard, i.e. /storage/emulated/0) and FIRST_FOLDER is /sdcard/FIRST.
 */
public class AppUtil {
    public static final File ROOT_FOLDER = new File("/sdcard");
    public static final File FIRST_FOLDER = new File(ROOT_FOLDER + "/FIRST/");

    public static AppUtil getInstance() {
        return new AppUtil();
    }
}
